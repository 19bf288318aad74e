#include "capture_table.hpp"

#include <cstdio>

#include <fmt/format.h>

#include "canemu/ipc/capture_writer.hpp"
#include "command.hpp"

namespace canemu::cli {

namespace {

std::string format_name(uint8_t format) {
  return std::string(ipc::to_string(static_cast<ipc::CaptureFormat>(format)));
}

// A JSON string's contents: quotes, backslashes and control characters escaped.
std::string json_escaped(const std::string& s) {
  std::string out;
  for (char ch : s) {
    if (ch == '"' || ch == '\\') {
      out += '\\';
      out += ch;
    } else if (static_cast<unsigned char>(ch) < 0x20) {
      out += fmt::format("\\u{:04x}", ch);
    } else {
      out += ch;
    }
  }
  return out;
}

}  // namespace

void print_recorders(const ipc::RecorderListReply& r) {
  std::printf("%-12s %-7s %10s %12s %7s %8s %s\n", "RECORDER", "FORMAT", "FRAMES", "BYTES",
              "ROTATED", "LOST", "FILE");
  for (uint16_t i = 0; i < r.count; ++i) {
    const ipc::RecorderEntry& e = r.recorders[i];
    const std::string error = ipc::name_of(e.error);
    std::printf("%-12s %-7s %10llu %12llu %7u %8llu %s%s\n", ipc::name_of(e.bus).c_str(),
                format_name(e.format).c_str(), static_cast<unsigned long long>(e.frames),
                static_cast<unsigned long long>(e.bytes), e.rotations,
                static_cast<unsigned long long>(e.lost), ipc::name_of(e.path).c_str(),
                error.empty() ? "" : ("  (" + error + ")").c_str());
  }
}

std::string recorders_json(const ipc::RecorderListReply& r) {
  std::string out = "[";
  for (uint16_t i = 0; i < r.count; ++i) {
    const ipc::RecorderEntry& e = r.recorders[i];
    out += fmt::format(
        "{}{{\"bus\":\"{}\",\"path\":\"{}\",\"format\":\"{}\",\"errors\":{},\"frames\":{},"
        "\"bytes\":{},\"rotations\":{},\"lost\":{},\"error\":\"{}\"}}",
        i ? "," : "", ipc::name_of(e.bus), json_escaped(ipc::name_of(e.path)),
        format_name(e.format), e.errors ? "true" : "false", e.frames, e.bytes, e.rotations, e.lost,
        json_escaped(ipc::name_of(e.error)));
  }
  return out + "]";
}

void print_bridges(const ipc::BridgeListReply& r) {
  std::printf("%-12s %-10s %-14s %4s %4s %10s %10s %7s %8s %8s %8s %8s %8s\n", "BRIDGE",
              "INTERFACE", "STATE", "TEC", "REC", "TO-IF", "FROM-IF", "ERRORS", "IF-DROP", "K-DROP",
              "Q-DROP", "REJECTED", "FAILED");
  for (uint16_t i = 0; i < r.count; ++i) {
    const ipc::BridgeEntry& e = r.bridges[i];
    const auto n = [](uint64_t v) { return static_cast<unsigned long long>(v); };
    std::printf("%-12s %-10s %-14s %4u %4u %10llu %10llu %7llu %8llu %8llu %8llu %8llu %8llu\n",
                ipc::name_of(e.bus).c_str(), ipc::name_of(e.interface).c_str(),
                state_name(e.state).c_str(), e.tec, e.rec, n(e.to_interface), n(e.from_interface),
                n(e.error_frames_written), n(e.to_interface_dropped), n(e.kernel_dropped),
                n(e.queue_dropped), n(e.rejected), n(e.tx_failed));
  }
}

std::string bridges_json(const ipc::BridgeListReply& r) {
  std::string out = "[";
  for (uint16_t i = 0; i < r.count; ++i) {
    const ipc::BridgeEntry& e = r.bridges[i];
    out += fmt::format(
        "{}{{\"kind\":\"socketcan\",\"bus\":\"{}\",\"interface\":\"{}\",\"error_frames\":{},"
        "\"state\":\"{}\",\"tec\":{},\"rec\":{},\"queued\":{},\"to_interface\":{},"
        "\"from_interface\":{},\"error_frames_written\":{},\"to_interface_dropped\":{},"
        "\"kernel_dropped\":{},\"queue_dropped\":{},\"rejected\":{},\"tx_failed\":{}}}",
        i ? "," : "", ipc::name_of(e.bus), json_escaped(ipc::name_of(e.interface)),
        e.error_frames ? "true" : "false", state_name(e.state), e.tec, e.rec, e.queued,
        e.to_interface, e.from_interface, e.error_frames_written, e.to_interface_dropped,
        e.kernel_dropped, e.queue_dropped, e.rejected, e.tx_failed);
  }
  return out + "]";
}

}  // namespace canemu::cli
