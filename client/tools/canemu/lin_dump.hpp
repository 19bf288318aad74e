// canemu dump on a LIN bus: the bus's frames and errors as an ephemeral VCI adapter's LIN
// controller (a responder with an empty response table, error messages on) sees them, one line
// each (docs/lin.md, "canemu dump"); canemu record and canemu dump into a file: the same as
// pcap records with LINKTYPE_LIN (docs/lin.md, "Recording a LIN bus").
#pragma once

#include <csignal>
#include <cstdint>
#include <string>

#include <vector>

#include "canemu/client/connection.hpp"
#include "canemu/ipc/lin_pcap.hpp"
#include "command.hpp"
#include "vci/lintype.h"

namespace canemu::cli {

// One message of a LIN monitor as a line, time stamped `at_ns` (on the dump's time base):
//   (0000000000.003333) lin0 10#A1A2 pid 50 enhanced checksum 8C
//   (0000000000.010250) lin0 wake-up
//   (0000000000.008333) lin0 error no-response
// Empty for what a dump does not show (its own controller's info messages, time overruns).
std::string lin_line(const LINMSG& m, int64_t at_ns, const std::string& bus);

// The LINKTYPE_LIN records of one monitor message: a frame (PID and checksum computed from
// its identifier, data and checksum kind; and the go-to-sleep event after the go-to-sleep
// command), an error (its bit; the VCI's error message tells no identifier or data: PID 0, no
// payload; no-bus-activity as the inactivity event), a wake-up event; nothing for the rest.
// A message that filled the monitor's FIFO (ovr) has the overflow bit.
std::vector<ipc::lin_pcap::Message> lin_pcap_messages(const LINMSG& m);

// Records LIN bus `run.bus` into `run.output` as pcap (LINKTYPE_LIN), with rotation, until
// `run.count` monitor messages that gave records (0: until interrupted) or `stop` is set.
int run_lin_record(client::Connection& c, const CaptureRun& run, const TimeBase& base,
                   volatile const std::sig_atomic_t& stop);

// Dumps LIN bus `bus` (`bitrate` 0: the rate of each header) until `count` lines (0: until
// interrupted) or `stop` is set.
int run_lin_dump(client::Connection& c, const std::string& bus, uint32_t bitrate, uint64_t count,
                 const TimeBase& base, volatile const std::sig_atomic_t& stop);

}  // namespace canemu::cli
