// The SL-CANi on a bus with an SJA1000 node: sending and answering, the service routines at
// their instants, the handle FIFO, repetition until acknowledged and sl064_clear_msg,
// _SL064_DISABLE_INT, the error routine and bus-off recovery, function 14's service requests
// and the interrupt lock (digest §6 items 9, 10, 26, 60-62, 65-70, 92-94, 99).
#include <gtest/gtest.h>

#include "adapters/sorcus/slcan_fixture.hpp"

namespace canemu::model::sorcus {
namespace {

using namespace testing;
using Bytes = std::vector<uint8_t>;

TEST(SlcanBus, TheManualsExampleSendsOnRequestAndAnswersRemoteFrames) {
  Slcan x;
  x.configure();
  const SL064Handle h = x.object(7, _SL064_SEND | _SL064_ACTIVE | _SL064_PASSIVE);
  ASSERT_EQ(x.diag(x.m.start_com()), kOk);
  ASSERT_EQ(x.diag(x.set(h, {0x11, 0x22})), kOk);
  x.run_until(100'000);
  EXPECT_TRUE(x.peer.log.received.empty());  // set_data does not send
  ASSERT_EQ(x.diag(x.m.send_data(h)), kOk);
  x.run_until(400'000);
  ASSERT_EQ(x.peer.log.received.size(), 1u);
  const auto& sent = x.peer.log.received[0];
  EXPECT_EQ(sent.frame, data_frame(7, {0x11, 0x22}));
  EXPECT_EQ(sent.at, 100'000 + frame_ns(sent.frame));
  // The routine (task 100, function 4) after the acknowledgement: at the frame's end.
  ASSERT_EQ(x.log.calls.size(), 1u);
  EXPECT_EQ(x.log.calls[0].at.ns(), sent.at);
  EXPECT_EQ(x.log.calls[0].task, kTask);
  EXPECT_EQ(x.log.calls[0].func, kFunc);
  EXPECT_EQ(x.log.calls[0].handle, h);
  // A remote frame: answered with the current data; the routine after the answer, not at the
  // remote frame.
  ASSERT_EQ(x.diag(x.set(h, {0x33})), kOk);
  x.peer.send(remote_frame(7, 1));
  x.run_until(800'000);
  ASSERT_EQ(x.peer.log.received.size(), 2u);
  const auto& answer = x.peer.log.received[1];
  EXPECT_EQ(answer.frame, data_frame(7, {0x33}));
  ASSERT_EQ(x.log.calls.size(), 2u);
  EXPECT_EQ(x.log.calls[1].at.ns(), answer.at);
  EXPECT_EQ(x.log.calls[1].handle, h);
  ULONG count = 0;
  EXPECT_EQ(x.diag(x.m.get_msg_count(h, count)), kOk);
  EXPECT_EQ(count, 2u);
}

TEST(SlcanBus, ReceiveObjectsTakeDataFramesAndAnswersToTheirRemoteFrames) {
  Slcan x;
  x.configure();
  const SL064Handle passive = x.object(0x30, _SL064_PASSIVE);
  const SL064Handle active = x.object(0x31, _SL064_ACTIVE);
  ASSERT_EQ(x.diag(x.m.start_com()), kOk);
  x.peer.send(data_frame(0x30, {1, 2, 3}));
  x.run_until(300'000);
  ASSERT_EQ(x.message_calls(), (std::vector<SL064Handle>{passive}));
  EXPECT_EQ(x.log.calls[0].at.ns(), frame_ns(data_frame(0x30, {1, 2, 3})));
  // Two bytes wanted, three came: two delivered, warning 1.
  std::array<uint8_t, 8> d{};
  uint8_t size = 2;
  EXPECT_EQ(x.diag(x.m.get_data(passive, d, size)), warning(1));
  EXPECT_EQ(size, 2);
  EXPECT_EQ(x.get(passive, 3), (Bytes{1, 2, 3}));
  // The active receive object's remote frame; the peer answers; the routine at the answer.
  ASSERT_EQ(x.diag(x.m.send_data_request(active)), kOk);
  x.run_until(600'000);
  ASSERT_EQ(x.peer.log.received.size(), 1u);
  EXPECT_EQ(x.peer.log.received[0].frame, remote_frame(0x31, 0));
  EXPECT_EQ(x.message_calls().size(), 1u);  // no event for the remote frame itself
  x.peer.send(data_frame(0x31, {9}));
  x.run_until(900'000);
  ASSERT_EQ(x.message_calls(), (std::vector<SL064Handle>{passive, active}));
  EXPECT_EQ(x.get(active, 1), (Bytes{9}));
}

TEST(SlcanBus, TheFifoHoldsHandlesSoTheDataSetAfterQueuingGo) {
  Slcan x;
  x.configure();
  std::vector<SL064Handle> h;
  for (ULONG id = 0x100; id < 0x10F; ++id) {
    h.push_back(x.object(id, _SL064_SEND | _SL064_ACTIVE));  // 15 objects: the temporary pool
  }
  ASSERT_EQ(x.diag(x.m.start_com()), kOk);
  for (std::size_t k = 0; k < 14; ++k) {
    ASSERT_EQ(x.diag(x.m.send_data(h[k])), kOk) << k;
  }
  EXPECT_EQ(x.diag(x.set(h[14], {0xAA})), kOk);
  EXPECT_EQ(x.diag(x.m.send_data(h[14])), warning(6));  // queued: not sent at once
  EXPECT_EQ(x.m.fifo_size(), 1u);
  EXPECT_EQ(x.diag(x.set(h[14], {0xBB, 0xCC})), kOk);  // after queuing
  x.run_until(5'000'000);
  ASSERT_EQ(x.peer.log.received.size(), 15u);
  // The 82527 sends by buffer number: 10Eh went from buffer 1, freed by 100h; 101h had been
  // chosen already when the interrupt loaded it.
  EXPECT_EQ(x.peer.log.received[0].frame, data_frame(0x100, {}));
  EXPECT_EQ(x.peer.log.received[1].frame, data_frame(0x101, {}));
  EXPECT_EQ(x.peer.log.received[2].frame, data_frame(0x10E, {0xBB, 0xCC}));
  EXPECT_EQ(x.m.fifo_size(), 0u);
}

TEST(SlcanBus, AFullFifoRefusesTheRequestWith2Bh) {
  Slcan x(false);  // nobody acknowledges: the temporary buffers stay busy
  x.configure();
  std::vector<SL064Handle> h;
  for (ULONG id = 0; id < 14 + SlcanModule::kFifoDepth + 1; ++id) {
    h.push_back(x.object(0x200 + id, _SL064_SEND | _SL064_ACTIVE));
  }
  ASSERT_EQ(x.diag(x.m.start_com()), kOk);
  for (std::size_t k = 0; k < 14; ++k) {
    ASSERT_EQ(x.diag(x.m.send_data(h[k])), kOk) << k;
  }
  for (std::size_t k = 14; k < 14 + SlcanModule::kFifoDepth; ++k) {
    ASSERT_EQ(x.diag(x.m.send_data(h[k])), warning(6)) << k;
  }
  EXPECT_EQ(x.diag(x.m.send_data(h.back())), error(0x2B));
  EXPECT_EQ(x.m.fifo_size(), SlcanModule::kFifoDepth);
}

TEST(SlcanBus, AnUnacknowledgedFrameRepeatsUntilClearMsg) {
  Slcan x(false);
  model::testing::NodeLog chip_log;
  x.m.chip().set_listener(&chip_log);
  x.configure();
  const SL064Handle h = x.object(0x55, _SL064_SEND | _SL064_ACTIVE);
  ASSERT_EQ(x.diag(x.m.start_com()), kOk);
  ASSERT_EQ(x.diag(x.m.send_data(h)), kOk);
  x.run_until(20'000'000);
  // Ack errors: TEC rises by 8 to 128 (error passive), then stays (the passive ACK-error
  // exception); the frame goes on and on, no routine is called, the buffer stays busy.
  const std::size_t errors = chip_log.errors.size();
  EXPECT_GT(errors, 100u);
  EXPECT_EQ(x.m.chip().confinement().tec(), 128);
  EXPECT_TRUE(x.message_calls().empty());
  ASSERT_EQ(x.log.calls.size(), 1u);  // the error routine at TEC 96: heavily disturbed
  EXPECT_EQ(x.log.calls[0].status, ULONG{SL064_STATUS_HEAVY});
  EXPECT_TRUE(x.m.buffer(1).busy);
  // A second send_data meanwhile: the request before is not yet on the bus.
  EXPECT_EQ(x.diag(x.m.send_data(h)), warning(3));
  EXPECT_EQ(x.diag(x.m.clear_msg(h)), kOk);
  EXPECT_FALSE(x.m.buffer(1).busy);
  EXPECT_EQ(x.m.fifo_size(), 0u);
  x.run_until(21'000'000);  // the attempt on the wire at the call ends
  const std::size_t after = chip_log.errors.size();
  x.run_until(40'000'000);
  EXPECT_EQ(chip_log.errors.size(), after);
  EXPECT_LE(after, errors + 1);
}

TEST(SlcanBus, ADisableIntObjectReportsNothingAndGivesWayToLaterRequests) {
  Slcan x(false);
  x.configure();
  std::vector<SL064Handle> h;
  for (ULONG id = 0x100; id < 0x10E; ++id) {
    h.push_back(x.object(id, _SL064_SEND | _SL064_ACTIVE));
  }
  const SL064Handle quiet = x.object(0x300, _SL064_SEND | _SL064_DISABLE_INT);  // the 15th
  ASSERT_EQ(x.diag(x.m.start_com()), kOk);
  ASSERT_EQ(x.diag(x.m.send_data(quiet)), kOk);
  for (std::size_t k = 0; k < 13; ++k) {
    ASSERT_EQ(x.diag(x.m.send_data(h[k])), kOk) << k;
  }
  // Every temporary buffer is busy; the 14th request takes the quiet object's.
  EXPECT_EQ(x.diag(x.m.send_data(h[13])), kOk);
  EXPECT_EQ(x.m.fifo_size(), 0u);
  for (uint8_t n = 1; n <= 14; ++n) {
    EXPECT_NE(x.m.buffer(n).id, 0x300u) << int(n);
  }
}

TEST(SlcanBus, ADisableIntObjectsTransmissionCausesNoInterrupt) {
  Slcan x;
  x.configure();
  const SL064Handle quiet = x.object(0x300, _SL064_SEND | _SL064_DISABLE_INT);
  ASSERT_EQ(x.diag(x.m.start_com()), kOk);
  ASSERT_EQ(x.diag(x.m.send_data(quiet)), kOk);
  x.run_until(1'000'000);
  ASSERT_EQ(x.peer.log.received.size(), 1u);
  EXPECT_TRUE(x.log.calls.empty());
  ULONG count = 9;
  EXPECT_EQ(x.diag(x.m.get_msg_count(quiet, count)), kOk);
  EXPECT_EQ(count, 0u);
}

TEST(SlcanBus, TheErrorRoutineGetsHeavyThenBusOffAndStopStartRecovers) {
  Slcan x;
  model::testing::NodeLog chip_log;
  x.m.chip().set_listener(&chip_log);
  ASSERT_TRUE(x.m.write_eeprom(SL064_EEPROM_TQ, 200));  // 250 kbit/s on a 500 kbit/s bus
  x.configure();
  const SL064Handle h = x.object(0x100, _SL064_SEND | _SL064_ACTIVE);
  ASSERT_EQ(x.diag(x.m.start_com()), kOk);
  ASSERT_EQ(x.diag(x.m.send_data(h)), kOk);
  Peer other(x.b);
  other.start();
  for (int k = 0; k < 100; ++k) {
    x.peer.send(data_frame(0x200, {1, 2, 3, 4}));
    other.send(data_frame(0x201, {1}));
  }
  x.run_until(60'000'000);
  auto off = std::find_if(chip_log.states.begin(), chip_log.states.end(),
                          [](const auto& s) { return s.second == ErrorState::bus_off; });
  ASSERT_NE(off, chip_log.states.end());
  ASSERT_EQ(x.log.calls.size(), 2u);
  EXPECT_EQ(x.log.calls[0].kind, SlcanServiceCall::Kind::error);
  EXPECT_EQ(x.log.calls[0].func, kErrFunc);
  EXPECT_EQ(x.log.calls[0].status, ULONG{SL064_STATUS_HEAVY});
  EXPECT_EQ(x.log.calls[1].status, ULONG{SL064_STATUS_BUS_OFF});
  EXPECT_EQ(x.log.calls[1].at.ns(), off->first);
  // start_com alone is out of order while running; stop, then start: counters 0 after
  // 128 x 11 recessive bits.
  EXPECT_EQ(x.diag(x.m.start_com()), error(0x2D));
  EXPECT_EQ(x.diag(x.m.clear_msg(h)), kOk);  // else the request goes again at the wrong rate
  EXPECT_EQ(x.diag(x.m.stop_com()), kOk);
  EXPECT_EQ(x.diag(x.m.start_com()), kOk);
  x.run_until(80'000'000);
  EXPECT_EQ(x.m.chip().confinement().tec(), 0);
  EXPECT_EQ(x.m.chip().confinement().rec(), 0);
  EXPECT_EQ(x.m.error_bits(), 0);
}

TEST(SlcanBus, Function14GivesServiceRequestsThatEvaluateSrqReads) {
  Slcan x;
  const USHORT task = x.m.driver_task();
  EXPECT_EQ(task, 0x41);
  x.configure(task, SL064_SRQ_SERVICE_FUNC);
  const SL064Handle h =
      x.object(7, _SL064_SEND | _SL064_ACTIVE, nullptr, task, SL064_SRQ_SERVICE_FUNC);
  ASSERT_EQ(x.diag(x.m.start_com()), kOk);
  SL064Handle got = 99;
  EXPECT_EQ(x.m.evaluate_srq(got), 0);
  EXPECT_EQ(got, 0);  // no SRQ
  ASSERT_EQ(x.diag(x.m.send_data(h)), kOk);
  x.run_until(500'000);
  ASSERT_EQ(x.log.requests.size(), 1u);
  EXPECT_EQ(x.log.requests[0], (std::pair<int64_t, USHORT>{frame_ns(data_frame(7, {})), 0x0180}));
  EXPECT_TRUE(x.log.calls.empty());
  EXPECT_EQ(x.m.evaluate_srq(got), 0);
  EXPECT_EQ(got, h);
  EXPECT_EQ(x.m.evaluate_srq(got), 0);
  EXPECT_EQ(got, 0);
}

TEST(SlcanBus, UnderTheInterruptLockTheFirstOfTwoFramesIsLost) {
  Slcan x;
  const USHORT task = x.m.driver_task();
  x.configure(0, 0);
  const SL064Handle h = x.object(0x40, _SL064_PASSIVE, nullptr, task, SL064_SRQ_SERVICE_FUNC);
  ASSERT_EQ(x.diag(x.m.start_com()), kOk);
  x.m.enable_int_mask();
  x.peer.send(data_frame(0x40, {1}));
  x.peer.send(data_frame(0x40, {2}));
  x.peer.send(data_frame(0x40, {3}));
  x.run_until(2'000'000);
  // The first frame's SRQ locked the interrupt: 2 and 3 came meanwhile, 3 overwrote 2.
  ASSERT_EQ(x.log.requests.size(), 1u);
  EXPECT_TRUE(x.m.locked());
  EXPECT_EQ(x.peer.log.sent.size(), 3u);
  std::array<uint8_t, 8> d{};
  uint8_t size = 1;
  EXPECT_EQ(x.diag(x.m.get_data(h, d, size)), warning(4));  // received, not yet handled
  EXPECT_EQ(d[0], 1);
  x.m.end_of_srq();
  x.run_until(2'000'000);
  ASSERT_EQ(x.log.requests.size(), 2u);
  EXPECT_EQ(x.log.requests[1].first, 2'000'000);
  size = 1;
  EXPECT_EQ(x.diag(x.m.get_data(h, d, size)), warning(5));  // one was lost
  EXPECT_EQ(d[0], 3);
  SL064Handle got = 0;
  EXPECT_EQ(x.m.evaluate_srq(got), 0);
  EXPECT_EQ(got, h);
  EXPECT_EQ(x.m.evaluate_srq(got), 0);
  EXPECT_EQ(got, h);
  ULONG count = 0;
  EXPECT_EQ(x.diag(x.m.get_msg_count(h, count)), kOk);
  EXPECT_EQ(count, 2u);
}

// Configured with one object (10h) and the acceptance mask open to every other identifier, its
// messages for routine `func` of `task`; communication started.
void start_with_open_mask(Slcan& x, USHORT task, USHORT func) {
  x.configure();
  x.object(0x10, _SL064_PASSIVE);
  ULONG mask = 0;  // everything
  ASSERT_EQ(x.diag(x.m.set_acceptance_mask(mask, 0, task, func)), kOk);
  ASSERT_EQ(x.diag(x.m.start_com()), kOk);
}

TEST(SlcanBus, UnconfiguredMessagesThroughTheMaskGoToItsRoutineWithHandle0) {
  Slcan x;
  ASSERT_NO_FATAL_FAILURE(start_with_open_mask(x, kTask, kFunc));
  x.peer.send(data_frame(0x123, {5}));
  x.run_until(500'000);
  ASSERT_EQ(x.message_calls(), (std::vector<SL064Handle>{0}));
  ULONG id = 0;
  EXPECT_EQ(x.diag(x.m.get_id(0, id)), kOk);
  EXPECT_EQ(id, 0x123u);
}

TEST(SlcanBus, EightUnconfiguredFramesBackToBackGiveEightCallsEachWithItsOwnId) {
  Slcan x;
  ASSERT_NO_FATAL_FAILURE(start_with_open_mask(x, kTask, kFunc));
  const std::vector<ULONG> ids = {0x101, 0x202, 0x303, 0x404, 0x505, 0x606, 0x707, 0x7EF};
  for (ULONG id : ids) {
    x.peer.send(data_frame(id, {1}));
  }
  x.run_until(2'000'000);  // all eight before anyone reads an ID
  ASSERT_EQ(x.message_calls(), std::vector<SL064Handle>(8, 0));
  std::vector<ULONG> got;
  for (const SlcanServiceCall& c : x.log.calls) {
    ULONG id = 0;
    EXPECT_EQ(x.diag(x.m.get_id(0, id, c.id)), kOk);
    got.push_back(id);
  }
  EXPECT_EQ(got, ids);
  ULONG last = 0;  // outside a routine: the last one
  EXPECT_EQ(x.diag(x.m.get_id(0, last)), kOk);
  EXPECT_EQ(last, 0x7EFu);
}

TEST(SlcanBus, WithFunction14AsTheMasksRoutineEachRequestKeepsItsFramesId) {
  Slcan x;
  ASSERT_NO_FATAL_FAILURE(start_with_open_mask(x, x.m.driver_task(), SL064_SRQ_SERVICE_FUNC));
  for (ULONG id : {0x111, 0x222, 0x333}) {
    x.peer.send(data_frame(id, {1}));
  }
  x.run_until(1'000'000);
  ASSERT_EQ(x.log.requests.size(), 3u);
  std::vector<ULONG> got;
  for (int i = 0; i < 3; ++i) {
    SL064Handle h = 9;
    EXPECT_EQ(x.m.evaluate_srq(h), 0);
    EXPECT_EQ(h, 0);
    ULONG id = 0;
    EXPECT_EQ(x.diag(x.m.get_id(0, id)), kOk);
    got.push_back(id);
  }
  EXPECT_EQ(got, (std::vector<ULONG>{0x111, 0x222, 0x333}));
}

}  // namespace
}  // namespace canemu::model::sorcus
