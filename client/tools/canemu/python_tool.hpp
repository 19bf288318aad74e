// The canemu commands that are Python underneath (plot: matplotlib; lin load: ldfparser; web:
// aiohttp; restbus load and dump --dbc: cantools) run `python3 -m MODULE` of the canemu package;
// CANEMU_PYTHON names another interpreter, and a canemu run from a build tree takes the
// repository's .venv/bin/python when there is one.
#pragma once

#include <string>
#include <vector>

namespace canemu::cli {

struct PythonRun {
  int status = -1;     // the exit status; -1 when it could not run or was killed
  std::string output;  // its standard output, when asked for
  std::string error;   // why it could not run
  std::string interpreter;
};

// CANEMU_PYTHON if set, else the build tree's .venv/bin/python if this canemu runs from one and
// it exists, else "python3".
std::string python_interpreter();

// `input` goes to the module's standard input (written whole before its output is read: one of
// the two should be small); its standard error stays the caller's.
PythonRun run_python_module(const std::string& module, const std::vector<std::string>& args,
                            const std::string& input, bool capture_output);

// Starts `python3 -m MODULE ARGS --ready-fd 3` as a filter of this process's standard output:
// once the module says on its descriptor 3 that it is ready (canemu.dbc_decode: the DBC is
// read), standard output goes into its standard input and `status` is 0, `pid` its process.
// When it ends without saying so (it printed why), `status` is its exit status and nothing
// changed; -1 with `error` when it could not run. finish_python_filter() ends the input and
// waits for it.
struct PythonFilter {
  int status = -1;
  int pid = -1;
  std::string error;
  std::string interpreter;
};
PythonFilter start_python_filter(const std::string& module, const std::vector<std::string>& args);
// Closes standard output (the filter's input) and waits for the filter: its exit status.
int finish_python_filter(const PythonFilter& filter);

// Replaces this process with `python3 -m MODULE ARGS` (python_interpreter() chooses which), for
// a module that runs as long as the command (canemu web); returns why only when that failed.
std::string exec_python_module(const std::string& module, const std::vector<std::string>& args);

}  // namespace canemu::cli
