#include "lin_dump.hpp"

#include <cstdio>
#include <cstring>
#include <span>

#include <fmt/format.h>

#include "canemu/firmware_model/bus/lin_frame.hpp"
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

}  // namespace

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
    const std::string line = *m ? lin_line((*m)->msg, (*m)->at_ns + base.offset_ns, bus) : "";
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
