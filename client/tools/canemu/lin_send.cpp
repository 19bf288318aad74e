#include "lin_send.hpp"

#include <cctype>
#include <cstdio>
#include <cstring>

#include <fmt/format.h>

#include "canemu/client/lists.hpp"
#include "lin_dump.hpp"
#include "lin_tap.hpp"

namespace canemu::cli {

namespace {

constexpr int64_t kStepNs = 1'000'000;  // stepped time moves 1 ms at a time while a frame runs

bool hex_byte(const std::string& text, std::size_t at, uint8_t& out) {
  if (at + 2 > text.size() || !std::isxdigit(static_cast<unsigned char>(text[at])) ||
      !std::isxdigit(static_cast<unsigned char>(text[at + 1]))) {
    return false;
  }
  out = static_cast<uint8_t>(std::stoul(text.substr(at, 2), nullptr, 16));
  return true;
}

}  // namespace

std::optional<LINMSG> parse_lin_send(const std::string& text, bool classic, std::string& error) {
  LINMSG m{};
  if (text == "sleep") {
    m.uMsgInfo.Bytes.bType = LIN_MSGTYPE_SLEEP;
    return m;
  }
  if (text == "wakeup") {
    m.uMsgInfo.Bytes.bType = LIN_MSGTYPE_WAKEUP;
    return m;
  }
  const std::size_t hash = text.find('#');
  uint8_t id = 0;
  if (hash != 2 || !hex_byte(text, 0, id) || id > 0x3F) {
    error =
        "a LIN frame is ID#DATA, ID# (the header alone), sleep or wakeup, with ID 00..3F in hex";
    return std::nullopt;
  }
  const std::string data = text.substr(hash + 1);
  if (data.size() % 2 != 0 || data.size() > 16) {
    error = "the data are 1 to 8 bytes of two hex digits each";
    return std::nullopt;
  }
  m.uMsgInfo.Bytes.bType = LIN_MSGTYPE_DATA;
  m.uMsgInfo.Bytes.bPid = id;
  m.uMsgInfo.Bytes.bDlen = static_cast<UINT8>(data.size() / 2);
  m.uMsgInfo.Bits.ecs = classic ? 0 : 1;
  m.uMsgInfo.Bits.ido = data.empty() ? 1 : 0;
  for (std::size_t i = 0; i < data.size() / 2; ++i) {
    if (!hex_byte(data, 2 * i, m.abData[i])) {
      error = "the data are 1 to 8 bytes of two hex digits each";
      return std::nullopt;
    }
  }
  return m;
}

std::optional<std::pair<ipc::WireBusKind, uint32_t>> bus_kind(client::Connection& c,
                                                              const std::string& bus) {
  auto s = client::fetch_status(c);
  for (std::size_t i = 0; s && i < s->buses.size(); ++i) {
    if (ipc::name_of(s->buses[i].name) == bus) {
      return std::make_pair(static_cast<ipc::WireBusKind>(s->buses[i].kind), s->buses[i].bitrate);
    }
  }
  return std::nullopt;
}

int run_lin_send(client::Connection& c, const std::vector<LINMSG>& frames, const LinSendOptions& o,
                 const TimeBase& base) {
  const auto kind = bus_kind(c, o.bus);
  auto tap = LinTap::open(c, o.bus, LIN_OPMODE_MASTER | LIN_OPMODE_ERRORS,
                          o.bitrate != 0 ? o.bitrate : (kind ? kind->second : 0));
  if (!tap) {
    return fail(tap.error().message);
  }
  // A node does not hear its own wake-up pulse: a listener of its own sees where one ends.
  std::optional<LinTap> listener;
  for (const LINMSG& frame : frames) {
    if (frame.uMsgInfo.Bytes.bType == LIN_MSGTYPE_WAKEUP && !listener) {
      auto l = LinTap::open(c, o.bus, LIN_OPMODE_ERRORS, 0);
      if (!l) {
        return fail(l.error().message);
      }
      listener.emplace(std::move(*l));
    }
  }
  int64_t stepped = 0;
  int errors = 0;
  for (const LINMSG& frame : frames) {
    auto w = ipc::make_message<ipc::VciRequest>();
    w.op = static_cast<uint16_t>(ipc::VciOp::lin_write);
    w.handle = tap->control();
    w.args[0] = 1;
    std::memcpy(w.payload, &frame, sizeof frame);
    if (auto r = vci_call(c, w); !r) {
      return fail(r.error().message);
    }
    // Its outcome: the frame with its identifier as the sender's monitor saw it (the
    // go-to-sleep command: 3Ch; a wake-up pulse: its end), or an error. Other frames are other
    // commanders' business.
    const uint8_t id =
        frame.uMsgInfo.Bytes.bType == LIN_MSGTYPE_SLEEP ? 0x3C : frame.uMsgInfo.Bytes.bPid;
    const bool wakeup = frame.uMsgInfo.Bytes.bType == LIN_MSGTYPE_WAKEUP;
    LinTap& watch = wakeup ? *listener : *tap;
    while (true) {
      auto m = watch.next(o.step_ns ? 0 : o.timeout_ms);
      if (!m) {
        return fail(m.error().message);
      }
      const uint8_t type = *m ? (*m)->msg.uMsgInfo.Bytes.bType : 0;
      const bool mine = wakeup ? type == LIN_MSGTYPE_WAKEUP
                               : type == LIN_MSGTYPE_DATA && (*m)->msg.uMsgInfo.Bytes.bPid == id;
      // The listener sees the errors of earlier frames too: a wake-up ends with its end only.
      if (*m && (mine || (!wakeup && type == LIN_MSGTYPE_ERROR))) {
        std::printf("%s\n", lin_line((*m)->msg, (*m)->at_ns + base.offset_ns, o.bus).c_str());
        errors += type == LIN_MSGTYPE_ERROR ? 1 : 0;
        break;
      }
      if (*m) {
        continue;  // info messages, other frames
      }
      if (!o.step_ns) {
        return fail(fmt::format("no outcome of a frame on {} in {} ms", o.bus, o.timeout_ms));
      }
      if (stepped + kStepNs > *o.step_ns) {
        return fail(fmt::format("a frame on {} was not done within the step", o.bus));
      }
      if (auto r = step_time(c, kStepNs); !r) {
        return fail(r.error().message);
      }
      stepped += kStepNs;
    }
  }
  if (o.step_ns && *o.step_ns > stepped) {
    if (auto r = step_time(c, *o.step_ns - stepped); !r) {
      return fail(r.error().message);
    }
  }
  return errors == 0 ? 0 : 1;
}

}  // namespace canemu::cli
