// What the bridges whose frames are messages (LCM, DDS) share beyond bridge_contract.hpp: their
// frame, error and state messages have the same fields (canemu_lcm/*.lcm, canemu_dds.idl), they
// publish the bridge's bus errors and states, and a bus has one such bridge of a kind. Run by
// lcm_bridge_test.cpp and dds_bridge_test.cpp.
#pragma once

#include <algorithm>
#include <cstdint>
#include <iterator>
#include <string>
#include <type_traits>
#include <vector>

#include <gtest/gtest.h>

#include "bridge_contract.hpp"

namespace canemu::daemon::bridge_test {

// The length of the data a DLC gives, and the DLC of a length (CAN FD's table above 8).
inline uint8_t dlc_of(uint8_t len) {
  static constexpr uint8_t kFdLengths[] = {12, 16, 20, 24, 32, 48, 64};
  uint8_t dlc = len <= 8 ? len : 9;
  for (std::size_t i = 0; len > 8 && i < std::size(kFdLengths) && kFdLengths[i] < len; ++i) {
    ++dlc;
  }
  return dlc;
}

// A published frame message of a frame in cansend's syntax.
template <class Message>
Message published(const std::string& cansend) {
  const ipc::socketcan::Frame f = cansend_frame(cansend);
  Message m{};
  m.id = f.can_id & CAN_EFF_MASK;  // as written: "800#" gives 12 bits in a standard identifier
  m.extended = (f.can_id & CAN_EFF_FLAG) != 0;
  m.remote = (f.can_id & CAN_RTR_FLAG) != 0;
  m.fd = f.fd;
  m.brs = (f.flags & CANFD_BRS) != 0;
  m.esi = (f.flags & CANFD_ESI) != 0;
  m.dlc = static_cast<decltype(m.dlc)>(dlc_of(f.len));
  m.len = static_cast<decltype(m.len)>(m.remote ? 0 : f.len);  // a remote frame's DLC only
  std::copy(f.data, f.data + f.len, m.data);
  return m;
}

// A published frame message as seen() gives it: candump's text, "@" its instant, " own" if the
// bridge's node sent it. Its DLC must give its length, and the bytes past it must be zero.
template <class Message>
std::string seen_text(const Message& m) {
  ipc::socketcan::Frame f;
  f.can_id = m.id | (m.extended ? CAN_EFF_FLAG : 0u) | (m.remote ? CAN_RTR_FLAG : 0u);
  f.fd = m.fd;
  f.flags = static_cast<uint8_t>((m.brs ? CANFD_BRS : 0) | (m.esi ? CANFD_ESI : 0));
  f.len = static_cast<uint8_t>(m.remote ? m.dlc : m.len);
  std::copy(m.data, m.data + 64, f.data);
  const std::string text = ipc::socketcan::candump_text(f);
  EXPECT_EQ(m.dlc, m.remote ? m.dlc : dlc_of(static_cast<uint8_t>(m.len))) << text;
  EXPECT_TRUE(
      std::all_of(m.data + (m.remote ? 0 : m.len), m.data + 64, [](auto b) { return b == 0; }))
      << text << ": bytes past its length";
  return text + "@" + std::to_string(m.timestamp_ns) + (m.from_tx ? " own" : "");
}

// Each message converted.
template <class Message, class Convert>
auto converted(const std::vector<Message>& messages, Convert convert) {
  std::vector<std::decay_t<decltype(convert(messages.front()))>> out;
  for (const Message& m : messages) {
    out.push_back(convert(m));
  }
  return out;
}

// A published bus error: what it was, where, and the counters after it.
struct PublishedError {
  std::string what;  // "ACK transmitter ACK in frame": type, role, field, in a frame or idle
  int tec = 0;
  int rec = 0;
  int64_t at_ns = 0;
};

template <class Message>
PublishedError published_error(const Message& e) {
  static const char* const kTypes[] = {"BIT", "STUFF", "FORM", "CRC", "ACK"};
  return {std::string(e.type < 5 ? kTypes[e.type] : "?") +
              (e.role == 0 ? " transmitter " : " receiver ") + std::string(e.field) +
              (e.in_frame ? " in frame" : " idle"),
          e.tec, e.rec, e.timestamp_ns};
}

// A published node state: "warning tec=96" (without its counter "warning"), or "restarted" for
// the restart after bus-off; "@" its instant.
template <class Message>
std::string published_state(const Message& s, bool with_tec = true) {
  static const char* const kStates[] = {"error-active", "warning", "error-passive", "bus-off"};
  const std::string what =
      s.restarted ? std::string("restarted") : std::string(s.state < 4 ? kStates[s.state] : "?");
  return what + (with_tec && !s.restarted ? " tec=" + std::to_string(s.tec) : "") + "@" +
         std::to_string(s.timestamp_ns);
}

// What the bridges whose frames are messages do (LCM, DDS): they publish bus errors and states,
// and a bus has one such bridge of a kind. An adapter as above, and
//   std::string second_bridge_error()          the refusal of a second bridge of can0
//   std::vector<PublishedError> errors(Bridge&, std::size_t count)
//   std::vector<std::string> states(Bridge&, std::size_t count, bool with_tec)
//                                              as published_state() gives them
template <class T>
class MessageBridges : public BridgeContract<T> {};

TYPED_TEST_SUITE_P(MessageBridges);

// Alone on the bus: no acknowledgement. 16 ACK errors take the transmitter to error-passive
// (warning at 96 on the way), where the passive ACK-error exception holds its counter.
TYPED_TEST_P(MessageBridges, AckErrorsAndTheStatesTheyLeadToArePublishedWithTheirInstants) {
  this->open(kClassic, "can0", 0, true);
  Bridge& bridge = *this->opened;
  this->transport.inject("123#1122");
  this->transport.deliver(bridge, 1);
  this->run_to(20'000'000);
  const std::vector<PublishedError> errors = this->transport.errors(bridge, 16);
  ASSERT_GE(errors.size(), 16u);
  EXPECT_EQ(errors[0].what, "ACK transmitter ACK in frame");  // the ACK slot
  EXPECT_EQ(errors[0].tec, 8);
  EXPECT_EQ(errors[0].rec, 0);
  EXPECT_EQ(
      this->transport.states(bridge, 2, true),
      (std::vector<std::string>{"warning tec=96@" + std::to_string(errors[11].at_ns),
                                "error-passive tec=128@" + std::to_string(errors[15].at_ns)}));
  EXPECT_EQ(bridge.stats().error_frames, errors.size() + 2);
  EXPECT_EQ(bridge.stats().to_interface_dropped, 0u);
}

TYPED_TEST_P(MessageBridges, OneBridgeOfAKindABus) {
  this->simulation = world(kTwoBuses);
  Simulation& sim = *this->simulation;
  ASSERT_TRUE(this->add(sim, "can0"));
  EXPECT_EQ(error_text(this->add(sim, "can0")), this->transport.second_bridge_error());
  ASSERT_TRUE(this->add(sim, "can1"));
  EXPECT_EQ(sim.bridges().size(), 2u);
}

REGISTER_TYPED_TEST_SUITE_P(MessageBridges,
                            AckErrorsAndTheStatesTheyLeadToArePublishedWithTheirInstants,
                            OneBridgeOfAKindABus);

}  // namespace canemu::daemon::bridge_test
