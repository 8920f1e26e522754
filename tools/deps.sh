# Sourced by tools/demo.sh and tools/test.sh: installs Debian packages that are missing.
# usage: ensure_packages pkg...   (apt-get as root, or through sudo; otherwise says what to do)

# The packages of pkg... that are not installed, on one line (each once).
missing_packages() {
  local p seen=" " out=()
  for p in "$@"; do
    case $seen in *" $p "*) continue ;; esac
    seen="$seen$p "
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || out+=("$p")
  done
  echo "${out[*]}"
}

packages_installed() {  # pkg...: true when every one is installed
  [ -z "$(missing_packages "$@")" ]
}

ensure_packages() {
  local missing=()
  read -r -a missing <<<"$(missing_packages "$@")"
  [ ${#missing[@]} -eq 0 ] && return 0
  echo "installing: ${missing[*]}"
  local sudo=""
  if [ "$(id -u)" -ne 0 ]; then
    if command -v sudo >/dev/null 2>&1; then
      sudo="sudo"
    else
      echo "not root and no sudo: please install ${missing[*]}" >&2
      return 1
    fi
  fi
  $sudo apt-get update -qq >/dev/null && \
    DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends \
      "${missing[@]}" >/dev/null
}
