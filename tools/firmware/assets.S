/* The example's built-in inputs, embedded byte for byte (GNU as .incbin), so the firmware
 * reads exactly the files the x86-64 golden tests read. Each macro is a quoted path:
 *   fw_case_json:  SPLINTCORE_FIRMWARE_CASE (fixtures/cases/paper_scale.json)
 *   fw_maxilla_stl, fw_mandible_stl: SPLINTCORE_FIRMWARE_MAXILLA / _MANDIBLE, the phantom jaws
 *     of `splintcore phantom --triangles 6000`, only when SPLINTCORE_FIRMWARE_WITH_JAWS is
 *     defined.
 * Each blob has a start label and a 32-bit size after it. */

  .section .rodata.splintcore_assets, "a"
  .balign 16
  .global fw_case_json
fw_case_json:
  .incbin SPLINTCORE_FIRMWARE_CASE
fw_case_json_end:
  .balign 4
  .global fw_case_json_size
fw_case_json_size:
  .4byte fw_case_json_end - fw_case_json

#if defined(SPLINTCORE_FIRMWARE_WITH_JAWS)
  .balign 16
  .global fw_maxilla_stl
fw_maxilla_stl:
  .incbin SPLINTCORE_FIRMWARE_MAXILLA
fw_maxilla_stl_end:
  .balign 4
  .global fw_maxilla_stl_size
fw_maxilla_stl_size:
  .4byte fw_maxilla_stl_end - fw_maxilla_stl

  .balign 16
  .global fw_mandible_stl
fw_mandible_stl:
  .incbin SPLINTCORE_FIRMWARE_MANDIBLE
fw_mandible_stl_end:
  .balign 4
  .global fw_mandible_stl_size
fw_mandible_stl_size:
  .4byte fw_mandible_stl_end - fw_mandible_stl
#endif

#if defined(__ELF__)
  .section .note.GNU-stack, "", %progbits
#endif
