// Running MeshLab (meshlabserver, under xvfb-run) as an independent oracle from the tests.
#ifndef SPLINTCORE_TESTS_MESHLAB_H
#define SPLINTCORE_TESTS_MESHLAB_H

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

namespace splintcore {
namespace test {

inline bool have_meshlab() {
  return std::system(
             "command -v meshlabserver >/dev/null 2>&1 && "
             "command -v xvfb-run >/dev/null 2>&1") == 0;
}

// Runs the filter script on the input meshes (layers in order) and returns MeshLab's log.
inline std::string meshlab_log(const std::vector<std::string>& inputs, const std::string& script) {
  const std::string log = inputs[0] + ".meshlab.log";
  std::string cmd = "xvfb-run -a meshlabserver";
  for (const std::string& in : inputs) cmd += " -i '" + in + "'";
  cmd += " -s '" + script + "' -l '" + log + "' >/dev/null 2>&1";
  EXPECT_EQ(std::system(cmd.c_str()), 0) << cmd;
  std::ifstream in(log);
  std::stringstream text;
  text << in.rdbuf();
  std::remove(log.c_str());
  return text.str();
}

// Writes bytes to a new temporary file with the given suffix and returns its path.
inline std::string temp_file(const std::vector<uint8_t>& bytes, const char* suffix = ".stl") {
  std::string path = std::string("/tmp/splintcore-meshlab-XXXXXX") + suffix;
  std::vector<char> name(path.begin(), path.end());
  name.push_back('\0');
  const int fd = mkstemps(name.data(), static_cast<int>(std::string(suffix).size()));
  EXPECT_GE(fd, 0);
  if (fd < 0) return "";
  EXPECT_EQ(write(fd, bytes.data(), bytes.size()), static_cast<ssize_t>(bytes.size()));
  close(fd);
  return name.data();
}

// The topology + geometry filters (fixtures/meshlab/topo.mlx) on an STL in memory.
inline std::string meshlab_log_of_bytes(const std::vector<uint8_t>& bytes) {
  const std::string path = temp_file(bytes);
  if (path.empty()) return "";
  std::string log = meshlab_log({path}, std::string(SPLINTCORE_FIXTURES_DIR) + "/meshlab/topo.mlx");
  std::remove(path.c_str());
  return log;
}

inline double number_after(const std::string& text, const std::string& label) {
  size_t at = text.find(label);
  if (at == std::string::npos) return std::nan("");
  return std::strtod(text.c_str() + at + label.size(), nullptr);
}

}  // namespace test
}  // namespace splintcore

#endif  // SPLINTCORE_TESTS_MESHLAB_H
