#include "lin_dump.hpp"

#include <cstdio>
#include <cstring>
#include <span>

#include <fmt/format.h>

#include "canemu/firmware_model/bus/lin_frame.hpp"
#include "canemu/ipc/ring_pair.hpp"
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

// One VCI request on the dump's connection; the daemon's text or the VCI result on failure.
client::Result<ipc::VciReply> vci(client::Connection& c, ipc::VciOp op, const std::string& device,
                                  uint32_t handle, std::initializer_list<uint32_t> args = {},
                                  std::vector<ipc::UniqueFd>* fds = nullptr) {
  auto m = ipc::make_message<ipc::VciRequest>();
  m.op = static_cast<uint16_t>(op);
  m.handle = handle;
  ipc::copy_name(m.device, device);
  std::size_t i = 0;
  for (uint32_t a : args) {
    m.args[i++] = a;
  }
  auto r = c.call<ipc::VciRequest, ipc::VciReply>(m);
  if (r && fds != nullptr) {
    *fds = c.take_fds();
  }
  if (r && r->hresult != VCI_OK) {
    return tl::unexpected(ipc::IpcError{
        EPROTO, fmt::format("canemud refused VCI request {}: 0x{:08X}", static_cast<int>(op),
                            static_cast<uint32_t>(r->hresult))});
  }
  return r;
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
  // An adapter of its own on the bus (gone with the connection), its monitor and controller.
  auto create = ipc::make_message<ipc::VciRequest>();
  create.op = static_cast<uint16_t>(ipc::VciOp::device_create);
  ipc::copy_name(reinterpret_cast<char(&)[ipc::kNameSize]>(create.payload), bus);
  auto created = c.call<ipc::VciRequest, ipc::VciReply>(create);
  if (!created || created->hresult != VCI_OK) {
    return fail(created ? fmt::format("canemud made no adapter on {}", bus)
                        : created.error().message);
  }
  char name_text[ipc::kNameSize] = {};
  std::memcpy(name_text, created->payload, sizeof name_text - 1);
  const std::string device = ipc::name_of(name_text);
  auto monitor = vci(c, ipc::VciOp::lin_monitor_open, device, 0);
  std::vector<ipc::UniqueFd> fds;
  auto init = monitor ? vci(c, ipc::VciOp::lin_monitor_init, device, monitor->handle, {4096}, &fds)
                      : monitor;
  if (!init) {
    return fail(init.error().message);
  }
  auto rings = ipc::RingPair::map(std::move(fds), sizeof(LINMSG));
  if (!rings) {
    return fail(rings.error().message);
  }
  ipc::RingReader rx = rings->rx().reader();
  rx.set_threshold(1);
  auto control = vci(c, ipc::VciOp::lin_control_open, device, 0);
  for (auto step :
       {ipc::VciOp::lin_monitor_activate, ipc::VciOp::lin_init, ipc::VciOp::lin_start}) {
    if (!control) {
      break;
    }
    const uint32_t handle =
        step == ipc::VciOp::lin_monitor_activate ? monitor->handle : control->handle;
    auto r = vci(c, step, device, handle, {LIN_OPMODE_ERRORS, bitrate});
    if (!r) {
      control = r;
    }
  }
  if (!control) {
    return fail(control.error().message);
  }
  // Time stamps count microseconds from the adapter's power-on, wrapping at 2^32.
  int64_t epoch_ns = 0;
  auto list = c.call<ipc::DeviceListRequest, ipc::DeviceListReply>(
      ipc::make_message<ipc::DeviceListRequest>());
  for (uint16_t i = 0; list && i < list->count; ++i) {
    if (ipc::name_of(list->devices[i].name) == device) {
      epoch_ns = list->devices[i].epoch_ns;
    }
  }
  std::fprintf(stderr, "canemu: listening on %s as %s (LIN, %s, time stamps in %s)\n", bus.c_str(),
               device.c_str(),
               bitrate == 0 ? "the rate of each header" : fmt::format("{} bit/s", bitrate).c_str(),
               base.wall_clock ? "wall-clock seconds" : "simulated seconds");
  uint64_t printed = 0;
  uint64_t wraps = 0;
  while (!stop && (count == 0 || printed < count)) {
    LINMSG m;
    const ipc::RingStatus status = rx.get(&m);
    if (status == ipc::RingStatus::empty) {
      rx.wait(200);
      continue;
    }
    if (status != ipc::RingStatus::ok) {
      return fail("the monitor's ring is corrupted");
    }
    if (m.uMsgInfo.Bytes.bType == LIN_MSGTYPE_TMOVR) {
      wraps += m.uMsgInfo.Bytes.bDlen;
      continue;
    }
    const int64_t at =
        epoch_ns + static_cast<int64_t>(((wraps << 32) | m.dwTime) * 1000) + base.offset_ns;
    const std::string line = lin_line(m, at, bus);
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
