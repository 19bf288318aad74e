// canemu record: a bus's frames and errors into a file, in candump log or pcap format (a LIN
// bus: pcap with LINKTYPE_LIN, lin_dump.hpp), with size-based rotation, until interrupted or
// --count frames. Unlike dump it is a silent observer by default (listen-only: it neither
// acknowledges nor signals errors, so recording changes nothing on the bus); --acknowledge makes
// it an active node (on a LIN bus the recorder only listens either way). canemud's own
// recorders ([[recorder]] in the configuration) write the same formats without a client.
#include <memory>
#include <string>

#include <CLI/CLI.hpp>

#include "command.hpp"

namespace canemu::cli {

Command add_record(CLI::App& app, const std::string& socket) {
  auto* record =
      app.add_subcommand("record", "record a bus's frames and errors into a candump log or pcap");
  auto o = std::make_shared<CaptureRun>();
  auto acknowledge = std::make_shared<bool>(false);
  o->record = true;
  record->add_option("BUS", o->bus, "bus name")->required();
  record->add_option("-o,--output", o->output, "the file (- for standard output)")->required();
  record
      ->add_option("--format", o->format,
                   "candump or pcap (default: pcap for a .pcap file and on a LIN bus, which "
                   "has no candump log; else candump)")
      ->check(CLI::IsMember({"candump", "pcap"}));
  record->add_option("-n,--count", o->count, "stop after this many frames");
  record->add_option("--max-size", o->max_bytes,
                     "start a new file before one grows past this many bytes (0: never)");
  record->add_option("--max-files", o->max_files,
                     "old files kept by rotation, FILE.1 the newest (default 10)");
  record->add_option("--bitrate", o->bitrate, "the recorder's bit/s (default: the bus's)");
  record->add_flag("--no-errors", o->no_errors, "frames only, no error frames");
  record->add_flag("--acknowledge", *acknowledge,
                   "an active node that acknowledges frames (default: listen-only)");
  record->add_flag("--sim-time", o->sim_time,
                   "time stamps in simulated seconds (default in real time: wall-clock seconds)");
  return {record, [&socket, o, acknowledge] {
            CaptureRun run = *o;
            run.listen_only = !*acknowledge;
            return run_capture(socket, run);
          }};
}

}  // namespace canemu::cli
