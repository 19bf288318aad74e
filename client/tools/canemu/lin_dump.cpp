#include "lin_dump.hpp"

#include <cstdio>
#include <cstring>
#include <optional>
#include <span>

#include <fmt/format.h>

#include "canemu/firmware_model/bus/lin_frame.hpp"
#include "canemu/ipc/capture_writer.hpp"
#include "lin_tap.hpp"
#include "vci/vcierr.h"

namespace canemu::cli {

namespace {

namespace lin = model::lin;

std::string error_name(uint8_t code) {
  switch (code) {
    case LIN_ERROR_BIT:
      return "bit";
    case LIN_ERROR_CHKSUM:
      return "checksum";
    case LIN_ERROR_PARITY:
      return "parity";
    case LIN_ERROR_SLNORE:
      return "no-response";
    case LIN_ERROR_SYNC:
      return "sync";
    case LIN_ERROR_NOBUS:
      return "no-bus-activity";
    default:
      return "other";
  }
}

namespace lp = ipc::lin_pcap;

}  // namespace

std::vector<lp::Message> lin_pcap_messages(const LINMSG& m) {
  const auto& b = m.uMsgInfo.Bytes;
  std::vector<lp::Message> out;
  lp::Message r;
  switch (b.bType) {
    case LIN_MSGTYPE_DATA: {
      const uint8_t id = b.bPid & lin::kMaxId;
      r.length = b.bDlen <= lin::kMaxData ? b.bDlen : lin::kMaxData;
      std::memcpy(r.data, m.abData, r.length);
      const auto kind = m.uMsgInfo.Bits.ecs ? lin::Checksum::enhanced : lin::Checksum::classic;
      r.pid = lin::protected_id(id);
      r.checksum = lin::checksum(kind, id, std::span<const uint8_t>(r.data, r.length));
      r.checksum_type =
          kind == lin::Checksum::enhanced ? lp::ChecksumType::enhanced : lp::ChecksumType::classic;
      if (id >= 0x3E) {
        r.errors |= lp::kErrorInvalidId;
      }
      out.push_back(r);
      if (id == lin::kMasterRequestId && r.length > 0 && r.data[0] == 0) {
        out.push_back(lp::event(lp::kEventGoToSleep));
      }
      break;
    }
    case LIN_MSGTYPE_ERROR:
      switch (m.abData[0]) {
        case LIN_ERROR_NOBUS:
          out.push_back(lp::event(lp::kEventInactivity));
          break;
        case LIN_ERROR_SLNORE:
          r.errors = lp::kErrorNoSlaveResponse;
          break;
        case LIN_ERROR_CHKSUM:
          r.errors = lp::kErrorChecksum;
          break;
        case LIN_ERROR_PARITY:
          r.errors = lp::kErrorParity;
          break;
        default:  // bit, sync, other
          r.errors = lp::kErrorFraming;
          break;
      }
      if (out.empty()) {
        out.push_back(r);
      }
      break;
    case LIN_MSGTYPE_WAKEUP:
      out.push_back(lp::event(lp::kEventWakeUp));
      break;
    default:
      break;
  }
  if (m.uMsgInfo.Bits.ovr && !out.empty() && out.front().type == lp::MessageType::frame) {
    out.front().errors |= lp::kErrorOverflow;
  }
  return out;
}

int run_lin_record(client::Connection& c, const CaptureRun& o, const TimeBase& base,
                   volatile const std::sig_atomic_t& stop) {
  // Errors are asked for always: the bus's inactivity comes as one (an event in the file).
  auto tap = LinTap::open(c, o.bus, LIN_OPMODE_ERRORS, o.bitrate);
  if (!tap) {
    return fail(tap.error().message);
  }
  auto out = ipc::CaptureWriter::open(
      {o.output, ipc::CaptureFormat::pcap, o.bus, o.max_bytes, o.max_files, true});
  if (!out) {
    return fail(out.error().message);
  }
  std::fprintf(
      stderr, "canemu: listening on %s as %s (LIN, %s, time stamps in %s)\n", o.bus.c_str(),
      tap->device().c_str(),
      o.bitrate == 0 ? "the rate of each header" : fmt::format("{} bit/s", o.bitrate).c_str(),
      base.wall_clock ? "wall-clock seconds" : "simulated seconds");
  uint64_t taken = 0;
  bool overflowed = false;
  std::optional<client::IpcError> gone;
  while (!stop && (o.count == 0 || taken < o.count)) {
    auto m = tap->next(200);
    if (!m) {
      return fail(m.error().message);
    }
    if (!*m) {
      if ((gone = c.lost())) {
        break;  // canemud closed the connection: nothing comes any more
      }
      continue;
    }
    const LINMSG& msg = (*m)->msg;
    if (o.no_errors && msg.uMsgInfo.Bytes.bType == LIN_MSGTYPE_ERROR &&
        msg.abData[0] != LIN_ERROR_NOBUS) {
      continue;
    }
    if (msg.uMsgInfo.Bits.ovr && !overflowed) {
      std::fprintf(stderr, "canemu: the monitor's FIFO is full: messages are being lost\n");
    }
    overflowed = msg.uMsgInfo.Bits.ovr != 0;
    const auto records = lin_pcap_messages(msg);
    if (records.empty()) {
      continue;
    }
    for (const lp::Message& r : records) {
      out->record((*m)->at_ns + base.offset_ns, r);
    }
    if (!out->flush()) {
      return fail(out->error() + fmt::format(" ({} record(s) lost)", out->lost()));
    }
    ++taken;
  }
  if (o.record) {
    std::fprintf(stderr, "canemu: %llu record(s) recorded in %s (pcap, LINKTYPE_LIN)\n",
                 static_cast<unsigned long long>(out->frames()), o.output.c_str());
  }
  return gone ? fail(gone->message) : 0;
}

std::string lin_line(const LINMSG& m, int64_t at_ns, const std::string& bus) {
  const std::string stamp =
      fmt::format("({:010}.{:06}) {}", at_ns / 1'000'000'000, at_ns % 1'000'000'000 / 1000, bus);
  const auto& b = m.uMsgInfo.Bytes;
  switch (b.bType) {
    case LIN_MSGTYPE_DATA: {
      const uint8_t id = b.bPid & lin::kMaxId;
      const uint8_t n = b.bDlen <= lin::kMaxData ? b.bDlen : lin::kMaxData;
      const auto kind = m.uMsgInfo.Bits.ecs ? lin::Checksum::enhanced : lin::Checksum::classic;
      std::string data;
      for (uint8_t i = 0; i < n; ++i) {
        data += fmt::format("{:02X}", m.abData[i]);
      }
      const bool sleep = id == lin::kMasterRequestId && n > 0 && m.abData[0] == 0;
      return fmt::format("{} {:02X}#{} pid {:02X} {} checksum {:02X}{}", stamp, id, data,
                         lin::protected_id(id),
                         kind == lin::Checksum::enhanced ? "enhanced" : "classic",
                         lin::checksum(kind, id, std::span<const uint8_t>(m.abData, n)),
                         sleep ? " go-to-sleep" : "");
    }
    case LIN_MSGTYPE_ERROR:
      return fmt::format("{} error {}", stamp, error_name(m.abData[0]));
    case LIN_MSGTYPE_WAKEUP:
      return stamp + " wake-up";
    default:
      return "";
  }
}

int run_lin_dump(client::Connection& c, const std::string& bus, uint32_t bitrate, uint64_t count,
                 const TimeBase& base, volatile const std::sig_atomic_t& stop) {
  // A responder with an empty response table and error messages: it listens.
  auto tap = LinTap::open(c, bus, LIN_OPMODE_ERRORS, bitrate);
  if (!tap) {
    return fail(tap.error().message);
  }
  std::fprintf(stderr, "canemu: listening on %s as %s (LIN, %s, time stamps in %s)\n", bus.c_str(),
               tap->device().c_str(),
               bitrate == 0 ? "the rate of each header" : fmt::format("{} bit/s", bitrate).c_str(),
               base.wall_clock ? "wall-clock seconds" : "simulated seconds");
  uint64_t printed = 0;
  while (!stop && (count == 0 || printed < count)) {
    auto m = tap->next(200);
    if (!m) {
      return fail(m.error().message);
    }
    if (!*m) {
      if (auto gone = c.lost()) {
        return fail(gone->message);  // canemud closed the connection: nothing comes any more
      }
      continue;
    }
    const std::string line = lin_line((*m)->msg, (*m)->at_ns + base.offset_ns, bus);
    if (line.empty()) {
      continue;
    }
    std::printf("%s\n", line.c_str());
    std::fflush(stdout);
    ++printed;
  }
  return 0;
}

}  // namespace canemu::cli
