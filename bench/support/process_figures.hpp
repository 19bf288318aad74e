// What the benchmarks of canemud read about a process and about their own run: a process's
// processor time and context switches (from /proc), and whether this is a smoke run.
#pragma once

#include <cstdint>
#include <exception>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <dirent.h>
#include <sys/types.h>

namespace canemu::bench {

// utime + stime in clock ticks, and voluntary + involuntary context switches, of a process.
inline std::pair<uint64_t, uint64_t> cpu_ticks_and_switches(pid_t pid) {
  std::ifstream stat("/proc/" + std::to_string(pid) + "/stat");
  std::string text((std::istreambuf_iterator<char>(stat)), std::istreambuf_iterator<char>());
  // Fields after the command's closing parenthesis: state is field 3, utime 14, stime 15.
  std::istringstream fields(text.substr(text.rfind(')') + 2));
  std::vector<std::string> f((std::istream_iterator<std::string>(fields)),
                             std::istream_iterator<std::string>());
  const uint64_t ticks = f.size() > 12 ? std::stoull(f[11]) + std::stoull(f[12]) : 0;
  std::ifstream status("/proc/" + std::to_string(pid) + "/status");
  uint64_t switches = 0;
  std::string line;
  while (std::getline(status, line)) {
    if (line.find("ctxt_switches:") != std::string::npos) {
      switches += std::stoull(line.substr(line.find(':') + 1));
    }
  }
  return {ticks, switches};
}

// The run time of a process in nanoseconds: the first field of /proc/PID/task/TID/schedstat
// (the scheduler's own account, to the nanosecond) summed over its threads. Threads that have
// ended are not counted, so take it around windows in which none ends.
inline uint64_t cpu_ns(pid_t pid) {
  const std::string tasks = "/proc/" + std::to_string(pid) + "/task";
  DIR* d = ::opendir(tasks.c_str());
  if (d == nullptr) {
    return 0;
  }
  uint64_t ns = 0;
  while (const dirent* e = ::readdir(d)) {
    if (e->d_name[0] == '.') {
      continue;
    }
    std::ifstream f(tasks + "/" + e->d_name + "/schedstat");
    uint64_t run = 0;
    if (f >> run) {
      ns += run;
    }
  }
  ::closedir(d);
  return ns;
}

// Whether --benchmark_min_time was given below Google Benchmark's default of 0.5 s (a smoke
// run, as CI's); Google Benchmark keeps the flag to itself.
inline bool smoke_run() {
  std::ifstream f("/proc/self/cmdline");
  std::string arg;
  while (std::getline(f, arg, '\0')) {
    constexpr std::string_view kFlag = "--benchmark_min_time=";
    if (arg.rfind(kFlag, 0) == 0) {
      try {
        return std::stod(arg.substr(kFlag.size())) < 0.5;
      } catch (const std::exception&) {
        return false;
      }
    }
  }
  return false;
}

}  // namespace canemu::bench
