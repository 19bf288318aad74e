// A shell command run for its output (popen): what it printed on stdout and how it ended.
#pragma once

#include <cstdio>
#include <string>

namespace canemu::testing {

struct ShellOutput {
  std::string out;
  int status = -1;  // pclose's: 0 when the command exited 0; -1 when it did not start
};

inline ShellOutput run_shell(const std::string& command) {
  ShellOutput r;
  FILE* f = ::popen(command.c_str(), "r");
  if (f == nullptr) {
    return r;
  }
  char line[256];
  while (std::fgets(line, sizeof line, f) != nullptr) {
    r.out += line;
  }
  r.status = ::pclose(f);
  return r;
}

}  // namespace canemu::testing
