// Channels through a real canemud: frames between clients with exact simulated timestamps,
// overrun when a reader stalls, clients that die or corrupt their rings, device notifications,
// and a byte-for-byte repeatable trace in stepped time.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <climits>
#include <csignal>
#include <fstream>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

#include "canemu/client/channel.hpp"
#include "canemu/ipc/clock.hpp"
#include "daemon_process.hpp"

namespace canemu {
namespace {

using testing::connect;
using testing::Daemon;
using testing::status;

constexpr int64_t kBit = 2000;  // ns at 500 kbit/s

client::Channel open(client::Connection& c, const std::string& bus, uint16_t flags = 0,
                     const std::string& device = {}, uint32_t rx_capacity = 0) {
  client::ChannelOptions o;
  o.bus = bus;
  o.flags = flags;
  o.device = device;
  o.rx_capacity = rx_capacity;
  auto ch = client::Channel::open(c, o);
  EXPECT_TRUE(ch) << ch.error().message;
  return std::move(*ch);
}

ipc::ChannelMessage frame(uint32_t id, std::vector<uint8_t> data, uint8_t flags = 0) {
  ipc::ChannelMessage m;
  m.id = id;
  m.flags = flags;
  m.dlc = static_cast<uint8_t>(data.size());
  std::copy(data.begin(), data.end(), m.data);
  return m;
}

void step(client::Connection& c, int64_t ns) {
  auto m = ipc::make_message<ipc::TimeStepRequest>();
  m.step_ns = ns;
  auto r = c.call<ipc::TimeStepRequest, ipc::TimeStepReply>(m);
  ASSERT_TRUE(r) << r.error().message;
}

std::vector<ipc::ChannelMessage> drain(client::Channel& ch) {
  std::vector<ipc::ChannelMessage> got;
  while (auto m = ch.receive(0)) {
    got.push_back(*m);
  }
  return got;
}

TEST(Channels, FramesGoBetweenClientsAtTheirExactSimulatedInstants) {
  Daemon d;
  auto ca = connect(d, "a");
  auto cb = connect(d, "b");
  auto a = open(ca, "can0", ipc::kChannelReportTx);
  auto b = open(cb, "can0");
  for (int i = 0; i < 3; ++i) {
    ASSERT_TRUE(a.send(frame(0x123, {0x11, 0x22})));
  }
  step(cb, 1'000'000);
  // 0x123 with two bytes is 62 bits to the end of EOF; 3 bits of intermission between frames.
  const auto rx = drain(b);
  ASSERT_EQ(rx.size(), 3u);
  const auto tx = drain(a);
  ASSERT_EQ(tx.size(), 3u);
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(rx[i].timestamp_ns, (62 + 65 * i) * kBit) << i;
    EXPECT_EQ(rx[i].kind, static_cast<uint8_t>(ipc::ChannelMessageKind::frame));
    EXPECT_EQ(rx[i].id, 0x123u);
    EXPECT_EQ(rx[i].dlc, 2);
    EXPECT_EQ(rx[i].data[1], 0x22);
    EXPECT_EQ(rx[i].lost_before, 0u);
    EXPECT_EQ(tx[i].kind, static_cast<uint8_t>(ipc::ChannelMessageKind::tx_done));
    EXPECT_EQ(tx[i].timestamp_ns, rx[i].timestamp_ns);
  }
  // Both ephemeral nodes show in the status, with their counts.
  const ipc::StatusReply s = status(ca);
  ASSERT_EQ(s.node_count, 5);  // after ixxat0's three controllers
  EXPECT_EQ(ipc::name_of(s.nodes[3].name), a.device() + ":0");
  EXPECT_EQ(s.nodes[3].frames_sent, 3u);
  EXPECT_EQ(s.nodes[4].frames_received, 3u);
  auto st = b.status();
  ASSERT_TRUE(st) << st.error().message;
  EXPECT_EQ(st->frames_received, 3u);
  EXPECT_EQ(st->rx_lost, 0u);
}

TEST(Channels, ExtendedRemoteAndSelfReceivedFramesKeepTheirFlags) {
  Daemon d;
  auto c = connect(d);
  auto a = open(c, "can1");
  auto b = open(c, "can1");
  ipc::ChannelMessage remote = frame(0x1ABCDEF, {}, ipc::kMsgExtended | ipc::kMsgRemote);
  remote.dlc = 4;
  ASSERT_TRUE(a.send(remote));
  ASSERT_TRUE(a.send(frame(0x10, {1, 2, 3}, ipc::kMsgSelfReception)));
  step(c, 1'000'000);
  const auto rx = drain(b);
  ASSERT_EQ(rx.size(), 2u);
  EXPECT_EQ(rx[0].id, 0x1ABCDEFu);
  EXPECT_EQ(rx[0].flags, ipc::kMsgExtended | ipc::kMsgRemote);
  EXPECT_EQ(rx[0].dlc, 4);
  const auto own = drain(a);
  ASSERT_EQ(own.size(), 1u);
  EXPECT_EQ(own[0].flags, ipc::kMsgOwn);
  EXPECT_EQ(own[0].timestamp_ns, rx[1].timestamp_ns);
}

TEST(Channels, AStalledReaderLosesWhatDoesNotFitAndIsToldHowMuch) {
  Daemon d;
  auto c = connect(d);
  auto a = open(c, "can0");
  // 96-byte elements: one page holds (4096 - 256) / 96 = 40.
  auto b = open(c, "can0", 0, {}, 40);
  ASSERT_EQ(b.info().rx_capacity, 40u);
  for (int round = 0; round < 2; ++round) {
    for (int i = 0; i < 25; ++i) {
      ASSERT_TRUE(a.send(frame(0x100 + round * 25 + i, {})));
    }
    step(c, 10'000'000);
  }
  auto st = b.status();
  ASSERT_TRUE(st);
  EXPECT_EQ(st->frames_received, 50u);
  EXPECT_EQ(st->rx_fill, 40u);
  EXPECT_EQ(st->rx_lost, 10u);
  EXPECT_EQ(b.rx().overruns(), 10u);
  auto got = drain(b);
  ASSERT_EQ(got.size(), 40u);
  EXPECT_EQ(got.back().id, 0x100u + 39);
  // The next message that fits says how many were lost before it.
  ASSERT_TRUE(a.send(frame(0x7FF, {})));
  step(c, 1'000'000);
  got = drain(b);
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].id, 0x7FFu);
  EXPECT_EQ(got[0].lost_before, 10u);
}

TEST(Channels, ElementsThatAreNotFramesAreCountedAndReported) {
  Daemon d;
  auto c = connect(d);
  auto a = open(c, "can0", ipc::kChannelReportTx);
  auto partner = open(c, "can0");              // acknowledges
  ipc::ChannelMessage bad = frame(0x800, {});  // 12 bits without the extended flag
  ASSERT_TRUE(a.send(bad));
  bad = frame(0x1, {});
  bad.dlc = 16;
  ASSERT_TRUE(a.send(bad));
  ASSERT_TRUE(a.send(frame(0x6, {1, 2}, ipc::kMsgFd)));  // the SJA1000 node is classic CAN
  ASSERT_TRUE(a.send(frame(0x5, {9})));
  step(c, 1'000'000);
  const auto got = drain(a);
  ASSERT_EQ(got.size(), 4u);
  EXPECT_EQ(got[0].kind, static_cast<uint8_t>(ipc::ChannelMessageKind::tx_dropped));
  EXPECT_EQ(got[0].id, 0x800u);
  EXPECT_EQ(got[1].kind, static_cast<uint8_t>(ipc::ChannelMessageKind::tx_dropped));
  EXPECT_EQ(got[2].kind, static_cast<uint8_t>(ipc::ChannelMessageKind::tx_dropped));
  EXPECT_EQ(got[2].id, 0x6u);
  EXPECT_EQ(got[3].kind, static_cast<uint8_t>(ipc::ChannelMessageKind::tx_done));
  EXPECT_EQ(got[3].id, 0x5u);
  auto st = a.status();
  ASSERT_TRUE(st);
  EXPECT_EQ(st->tx_rejected, 3u);
}

TEST(Channels, AMismatchedBitRateDisruptsTheBusAndErrorsAreReported) {
  Daemon d;
  auto c = connect(d);
  auto receiver = open(c, "can1");  // at the bus's 500 kbit/s
  client::ChannelOptions o;
  o.bus = "can1";
  o.bitrate = 250000;
  o.flags = ipc::kChannelReportErrors;
  auto slow = client::Channel::open(c, o);
  ASSERT_TRUE(slow) << slow.error().message;
  EXPECT_EQ(slow->info().bitrate, 250000u);
  ASSERT_TRUE(slow->send(frame(0x10, {1})));
  step(c, 3'000'000);
  // Every attempt of the 250 kbit/s node ends in a bit error as transmitter, 152 us apart, as
  // long as the 500 kbit/s receiver answers with active error flags; the 12th error takes TEC
  // to the warning limit. By then the receiver's REC has passed 127: its passive error flags no
  // longer disturb the transmitter, which now misses the ACK nobody at its rate gives: an ACK
  // error takes it to error-passive at TEC 128, where further ACK errors do not count.
  std::vector<ipc::ChannelMessage> errors;
  std::vector<ipc::ChannelMessage> states;
  for (const auto& m : drain(*slow)) {
    (m.kind == static_cast<uint8_t>(ipc::ChannelMessageKind::bus_error) ? errors : states)
        .push_back(m);
  }
  ASSERT_EQ(errors.size(), 17u);
  for (std::size_t k = 0; k < 15; ++k) {
    EXPECT_EQ(errors[k].timestamp_ns, 84'000 + 152'000 * static_cast<int64_t>(k)) << k;
    EXPECT_EQ(errors[k].error_type, 0) << k;  // bit error
    EXPECT_EQ(errors[k].error_role, 0) << k;  // as transmitter
    EXPECT_EQ(errors[k].tec, 8 * (k + 1)) << k;
  }
  for (std::size_t k = 15; k < 17; ++k) {
    EXPECT_EQ(errors[k].error_type, 4) << k;  // ACK error
    EXPECT_EQ(errors[k].tec, 128) << k;
  }
  EXPECT_EQ(errors[15].timestamp_ns, 2'472'000);
  EXPECT_EQ(errors[16].timestamp_ns, 2'764'000);
  ASSERT_EQ(states.size(), 2u);
  EXPECT_EQ(states[0].state, static_cast<uint8_t>(ipc::WireErrorState::warning));
  EXPECT_EQ(states[0].timestamp_ns, errors[11].timestamp_ns);
  EXPECT_EQ(states[1].state, static_cast<uint8_t>(ipc::WireErrorState::passive));
  EXPECT_EQ(states[1].tec, 128);
  EXPECT_EQ(states[1].timestamp_ns, errors[15].timestamp_ns);
  const ipc::StatusReply s = status(c);
  EXPECT_GT(s.buses[1].error_frames, 0u);
}

TEST(Channels, BadOpenAndCloseRequestsAreRefusedByName) {
  Daemon d;
  auto c = connect(d);
  client::ChannelOptions o;
  o.bus = "nope";
  auto r = client::Channel::open(c, o);
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("no_such_bus"), std::string::npos) << r.error().message;
  o.bus = "can0";
  o.bitrate = 123457;
  r = client::Channel::open(c, o);
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("bad_bit_timing"), std::string::npos) << r.error().message;
  o.bitrate = 0;
  o.device = "ixxat0";
  r = client::Channel::open(c, o);
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("name_in_use"), std::string::npos) << r.error().message;
  o.device = "bad name";
  r = client::Channel::open(c, o);
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("bad_argument"), std::string::npos) << r.error().message;
  o.device = {};
  o.flags = 0x100;
  r = client::Channel::open(c, o);
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("unknown flags"), std::string::npos) << r.error().message;
  auto close = ipc::make_message<ipc::CloseChannelRequest>();
  close.channel = 77;
  auto cr = c.call<ipc::CloseChannelRequest, ipc::CloseChannelReply>(close);
  ASSERT_FALSE(cr);
  EXPECT_NE(cr.error().message.find("no_such_channel"), std::string::npos);
  // Nothing of it left a device behind.
  EXPECT_EQ(status(c).node_count, 3);
}

TEST(Channels, DevicesComeAndGoWithNotifications) {
  Daemon d;
  auto watcher = connect(d, "watcher");
  ASSERT_TRUE(watcher.subscribe(ipc::kEventDevices));
  auto c = connect(d, "owner");
  {
    auto ch = open(c, "can1", 0, "tester");
    auto added = watcher.next_notification(5000);
    ASSERT_TRUE(added);
    EXPECT_EQ(added->kind, static_cast<uint32_t>(ipc::NotificationKind::device_added));
    EXPECT_EQ(ipc::name_of(added->device), "tester");
    auto list = watcher.call<ipc::DeviceListRequest, ipc::DeviceListReply>(
        ipc::make_message<ipc::DeviceListRequest>());
    ASSERT_TRUE(list);
    ASSERT_EQ(list->count, 2);
    EXPECT_EQ(ipc::name_of(list->devices[0].name), "ixxat0");
    EXPECT_EQ(list->devices[0].controller_count, 3);  // and the LIN controller
    EXPECT_EQ(ipc::name_of(list->devices[0].buses[1]), "can1");
    EXPECT_EQ(ipc::name_of(list->devices[1].name), "tester");
    EXPECT_EQ(list->devices[1].ephemeral, 1);
    EXPECT_EQ(list->devices[1].owner_pid, static_cast<uint32_t>(::getpid()));
    EXPECT_EQ(list->generation, added->generation);
    auto clients = watcher.call<ipc::ClientListRequest, ipc::ClientListReply>(
        ipc::make_message<ipc::ClientListRequest>());
    ASSERT_TRUE(clients);
    ASSERT_EQ(clients->count, 2);
    EXPECT_EQ(ipc::name_of(clients->clients[1].name), "owner");
    EXPECT_EQ(clients->clients[1].channels, 1u);
  }  // closed
  auto removed = watcher.next_notification(5000);
  ASSERT_TRUE(removed);
  EXPECT_EQ(removed->kind, static_cast<uint32_t>(ipc::NotificationKind::device_removed));
  EXPECT_EQ(ipc::name_of(removed->device), "tester");
  EXPECT_EQ(status(watcher).node_count, 3);
}

// A client killed while its channel is busy: its device goes, and a new client reuses the node.
TEST(Channels, AClientThatDiesIsCleanedUp) {
  Daemon d;
  auto watcher = connect(d, "watcher");
  ASSERT_TRUE(watcher.subscribe(ipc::kEventDevices));
  int ready[2];
  ASSERT_EQ(::pipe(ready), 0);
  const pid_t child = ::fork();
  if (child == 0) {
    auto c = client::Connection::open(d.socket(), "doomed");
    if (!c) {
      ::_exit(1);
    }
    client::ChannelOptions o;
    o.bus = "can0";
    o.device = "doomed";
    auto ch = client::Channel::open(*c, o);
    if (!ch) {
      ::_exit(2);
    }
    for (int i = 0; i < 20; ++i) {
      (void)ch->send(frame(0x42, {1, 2}));
    }
    (void)!::write(ready[1], "x", 1);
    ::pause();
    ::_exit(0);
  }
  ::close(ready[1]);
  char x;
  ASSERT_EQ(::read(ready[0], &x, 1), 1);
  ::close(ready[0]);
  auto added = watcher.next_notification(5000);
  ASSERT_TRUE(added);
  ::kill(child, SIGKILL);
  ::waitpid(child, nullptr, 0);
  auto removed = watcher.next_notification(5000);
  ASSERT_TRUE(removed);
  EXPECT_EQ(removed->kind, static_cast<uint32_t>(ipc::NotificationKind::device_removed));
  EXPECT_EQ(ipc::name_of(removed->device), "doomed");
  // Its frames stay unsent; the bus goes on with a new client on the same node.
  auto c = connect(d);
  auto again = open(c, "can0", ipc::kChannelReportTx, "doomed");
  auto partner = open(c, "can0");  // acknowledges
  ASSERT_TRUE(again.send(frame(0x43, {})));
  step(c, 1'000'000);
  const auto got = drain(again);
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].id, 0x43u);
  const ipc::StatusReply s = status(c);
  EXPECT_EQ(s.node_count, 5);  // ixxat0's three controllers, doomed's node again, the partner
  EXPECT_EQ(s.nodes[3].frames_sent, 1u);
}

// A client that writes nonsense into its ring positions is disconnected; others go on.
TEST(Channels, CorruptedRingPositionsDisconnectOnlyThatClient) {
  Daemon d;
  auto good = connect(d, "good");
  auto sender = open(good, "can0");
  for (int which = 0; which < 2; ++which) {
    auto bad = connect(d, "bad");
    auto ch = open(bad, "can0");
    ipc::RingHeader* hdr = which == 0 ? ch.rx_header() : ch.tx_header();
    if (which == 0) {
      // The receive ring's read position far ahead of what the daemon wrote.
      hdr->read_pos.store(1'000'000);
      ASSERT_TRUE(sender.send(frame(0x1, {})));
    } else {
      // The transmit ring's write position beyond its capacity; the doorbell makes the daemon
      // look.
      hdr->write_pos.store(1'000'000);
      const uint64_t one = 1;
      ASSERT_EQ(::write(ch.tx_doorbell_fd(), &one, sizeof one), 8);
    }
    step(good, 1'000'000);
    // The daemon closed the bad connection.
    std::vector<uint8_t> buffer;
    auto n = ipc::receive_packet(bad.fd(), buffer, 5000);
    ASSERT_TRUE(n) << n.error().message;
    EXPECT_EQ(*n, 0u) << which;
    EXPECT_EQ(status(good).node_count, 4) << which;
  }
}

// A client that fills its transmit ring with nothing but junk gets it rejected a slice at a time;
// the daemon keeps serving everyone meanwhile.
TEST(Channels, AFloodOfJunkIsRejectedWithoutHoldingTheLoop) {
  Daemon d;
  auto c = connect(d);
  auto other = connect(d, "other");
  client::ChannelOptions o;
  o.bus = "can0";
  o.tx_capacity = 2000;
  auto junk = client::Channel::open(c, o);
  ASSERT_TRUE(junk) << junk.error().message;
  ipc::ChannelMessage bad = frame(0x1, {});
  bad.dlc = 16;
  for (int i = 0; i < 2000; ++i) {
    ASSERT_TRUE(junk->send(bad));
  }
  step(c, 1'000'000);
  EXPECT_EQ(status(other).bus_count, 3);
  uint64_t rejected = 0;
  for (int k = 0; k < 1000 && rejected < 2000; ++k) {
    auto st = junk->status();
    ASSERT_TRUE(st);
    rejected = st->tx_rejected;
  }
  EXPECT_EQ(rejected, 2000u);
}

// Ring memory is limited daemon-wide: the channel that would pass 256 MiB is refused.
TEST(Channels, RingMemoryHasADaemonWideLimit) {
  Daemon d;
  auto c1 = connect(d, "one");
  auto c2 = connect(d, "two");
  client::ChannelOptions o;
  o.bus = "can0";
  o.rx_capacity = 65535;
  o.tx_capacity = 65535;
  std::vector<client::Channel> held;
  for (int i = 0; i < 21; ++i) {  // 21 x 2 x 65535 x 96 bytes: 252 MiB
    auto ch = client::Channel::open(i < 16 ? c1 : c2, o);
    ASSERT_TRUE(ch) << i << ": " << ch.error().message;
    held.push_back(std::move(*ch));
  }
  auto refused = client::Channel::open(c2, o);
  ASSERT_FALSE(refused);
  EXPECT_NE(refused.error().message.find("no_resources"), std::string::npos)
      << refused.error().message;
  held.pop_back();  // closing one frees its share
  EXPECT_TRUE(client::Channel::open(c2, o));
}

// In real time nobody steps: the doorbell wakes the daemon for an idle node, the node pulls the
// rest as it finishes each frame, and the receiver blocks until frames come.
TEST(Channels, InRealTimeFramesFlowWithoutSteps) {
  Daemon d("realtime");
  auto ca = connect(d, "a");
  auto cb = connect(d, "b");
  auto a = open(ca, "can0", ipc::kChannelReportTx);
  auto b = open(cb, "can0");
  for (int burst = 0; burst < 3; ++burst) {
    for (int i = 0; i < 100; ++i) {
      ASSERT_TRUE(a.send(frame(0x300 + i, {static_cast<uint8_t>(i)}), 5000));
    }
    int64_t last = 0;
    for (int i = 0; i < 100; ++i) {
      auto m = b.receive(5000);
      ASSERT_TRUE(m) << "burst " << burst << " frame " << i;
      EXPECT_EQ(m->id, 0x300u + i);
      EXPECT_GT(m->timestamp_ns, last);
      last = m->timestamp_ns;
      auto done = a.receive(5000);
      ASSERT_TRUE(done);
      EXPECT_EQ(done->timestamp_ns, m->timestamp_ns);
    }
  }
}

// In real time a frame starts when its client queued it, not when canemud got round to it: the
// client's ring notes when it rang the doorbell, and canemud kicks the channel at that instant
// (docs/daemon.md, "Time"), unless that was more than 10 ms before it woke. canemud is stopped
// (SIGSTOP) while the client queues a frame and for a while after; the frame's start of frame
// is placed on the wall clock through canemud's start, bounded by status answers (a sample's
// simulated time against the wall clock before the request and after the answer).
TEST(Channels, InRealTimeAFrameStartsWhenItsClientQueuedItNotWhenCanemudWoke) {
  Daemon d("realtime");
  auto ca = connect(d, "a");
  auto cb = connect(d, "b");
  auto a = open(ca, "can0");
  auto b = open(cb, "can0");
  // canemud's start on CLOCK_MONOTONIC lies in [lower, upper]: the tightest of several answers.
  int64_t lower = INT64_MIN;
  int64_t upper = INT64_MAX;
  auto bound_start = [&] {
    for (int i = 0; i < 8; ++i) {
      const int64_t asked = ipc::monotonic_ns();
      const int64_t sim = status(ca).sim_time_ns;
      const int64_t answered = ipc::monotonic_ns();
      lower = std::max(lower, asked - sim);
      upper = std::min(upper, answered - sim);
    }
  };
  auto stopped = [&] {
    std::ifstream stat("/proc/" + std::to_string(d.pid()) + "/stat");
    std::string line;
    std::getline(stat, line);
    return line.substr(line.rfind(')') + 2, 1) == "T";
  };
  // Queues a frame while canemud is stopped, and lets it run again `pause_ns` later; the frame's
  // start of frame as bounds on the wall clock, and the instants the frame was queued and
  // canemud let run.
  struct Run {
    int64_t sof_from, sof_to, queued_from, queued_to, resumed;
  };
  auto run = [&](uint32_t id, int64_t pause_ns) {
    bound_start();
    EXPECT_EQ(::kill(d.pid(), SIGSTOP), 0);
    const int64_t deadline = ipc::monotonic_ns() + 5'000'000'000;
    while (!stopped() && ipc::monotonic_ns() < deadline) {
      std::this_thread::yield();
    }
    EXPECT_TRUE(stopped());
    Run r{};
    r.queued_from = ipc::monotonic_ns();
    EXPECT_TRUE(a.send(frame(id, {0x11, 0x22})));
    r.queued_to = ipc::monotonic_ns();
    std::this_thread::sleep_for(std::chrono::nanoseconds(pause_ns));  // canemud kept stopped
    r.resumed = ipc::monotonic_ns();
    EXPECT_EQ(::kill(d.pid(), SIGCONT), 0);
    auto m = b.receive(5000);
    EXPECT_TRUE(m);
    bound_start();
    // 0x123 or 0x124 with two bytes: 62 bits (124 us) from SOF to the end of EOF.
    const int64_t sof = (m ? m->timestamp_ns : 0) - 62 * kBit;
    r.sof_from = lower + sof;
    r.sof_to = upper + sof;
    return r;
  };
  // Stopped 2 ms: the frame started as it was queued, before canemud ran again.
  const Run soon = run(0x123, 2'000'000);
  EXPECT_LT(soon.sof_to, soon.resumed);
  EXPECT_GE(soon.sof_to, soon.queued_from);
  // Stopped 30 ms: a ring's note older than 10 ms is not taken; the frame starts once canemud runs.
  const Run late = run(0x124, 30'000'000);
  EXPECT_GE(late.sof_from, late.queued_to + 10'000'000);
}

// Threads that share one channel take turns with lock()/unlock(): nothing is lost or doubled.
TEST(Channels, ThreadsSharingAChannelTakeTurnsWithLockAndUnlock) {
  Daemon d;
  auto c = connect(d);
  client::ChannelOptions o;
  o.bus = "can0";
  o.tx_capacity = 1200;
  o.rx_capacity = 1200;
  auto shared = client::Channel::open(c, o);
  ASSERT_TRUE(shared) << shared.error().message;
  auto rx = open(c, "can0", 0, {}, 1200);
  constexpr int kPerThread = 500;
  auto work = [&](uint32_t base) {
    for (int i = 0; i < kPerThread; ++i) {
      std::lock_guard<client::Channel> hold(*shared);
      ASSERT_TRUE(shared->send(frame(base + static_cast<uint32_t>(i), {})));
    }
  };
  std::thread t1(work, 0x000);
  std::thread t2(work, 0x400);
  t1.join();
  t2.join();
  step(c, 1'000'000'000);
  std::vector<bool> seen(0x800, false);
  int count = 0;
  while (auto m = rx.receive(0)) {
    ASSERT_FALSE(seen[m->id]) << m->id;
    seen[m->id] = true;
    ++count;
  }
  EXPECT_EQ(count, 2 * kPerThread);
}

// Same configuration, same inputs: the same bytes, twice.
TEST(Channels, SteppedTimeGivesTheSameTraceByteForByte) {
  auto run = [] {
    Daemon d;
    auto c = connect(d);
    auto monitor = open(c, "can0", ipc::kChannelListenOnly);
    auto a = open(c, "can0", ipc::kChannelReportTx);
    auto b = open(c, "can0", ipc::kChannelReportTx);
    for (int i = 0; i < 10; ++i) {
      (void)a.send(frame(0x200 + i, {static_cast<uint8_t>(i)}));
      (void)b.send(
          frame(0x1F0 + i, {static_cast<uint8_t>(i), 0xAA}, i % 2 ? ipc::kMsgExtended : 0));
      step(c, 150'000);
    }
    step(c, 10'000'000);
    std::vector<uint8_t> trace;
    for (auto* ch : {&monitor, &a, &b}) {
      for (const auto& m : drain(*ch)) {
        const auto* p = reinterpret_cast<const uint8_t*>(&m);
        trace.insert(trace.end(), p, p + sizeof m);
      }
    }
    return trace;
  };
  const auto first = run();
  const auto second = run();
  // The monitor sees 20 frames; each sender its 10 confirmations and the other's 10 frames.
  EXPECT_EQ(first.size(), (20 + 20 + 20) * sizeof(ipc::ChannelMessage));
  EXPECT_EQ(first, second);
}

// A scenario with random hits, loaded at run time, repeats byte for byte with the same seed, and
// its errors are in the trace.
TEST(Channels, AScenarioWithRandomHitsRepeatsByteForByte) {
  const std::string text =
      "[scenario]\nname = \"noise\"\nseed = 3\n\n[[fault]]\nat = \"0s\"\nbus = \"can0\"\n"
      "effect = \"stuff_error\"\nprobability = 0.3\n";
  auto run = [&] {
    Daemon d;
    auto c = connect(d);
    auto load = std::make_unique<ipc::FaultLoadRequest>(ipc::make_message<ipc::FaultLoadRequest>());
    load->length = static_cast<uint32_t>(text.size());
    std::copy(text.begin(), text.end(), load->text);
    auto loaded = c.call<ipc::FaultLoadRequest, ipc::FaultLoadReply>(*load);
    EXPECT_TRUE(loaded && loaded->applied == 1) << (loaded ? loaded->errors : "no reply");
    auto monitor = open(c, "can0", ipc::kChannelListenOnly | ipc::kChannelReportErrors);
    auto a = open(c, "can0", ipc::kChannelReportTx | ipc::kChannelReportErrors);
    for (int i = 0; i < 30; ++i) {
      (void)a.send(frame(0x300 + i, {static_cast<uint8_t>(i)}));
    }
    step(c, 20'000'000);
    std::vector<uint8_t> trace;
    std::size_t errors = 0;
    for (auto* ch : {&monitor, &a}) {
      for (const auto& m : drain(*ch)) {
        errors += m.kind == static_cast<uint8_t>(ipc::ChannelMessageKind::bus_error);
        const auto* p = reinterpret_cast<const uint8_t*>(&m);
        trace.insert(trace.end(), p, p + sizeof m);
      }
    }
    auto list = c.call<ipc::FaultListRequest, ipc::FaultListReply>(
        ipc::make_message<ipc::FaultListRequest>());
    EXPECT_TRUE(list && list->count == 1);
    return std::make_tuple(trace, errors, list ? list->faults[0].hits : 0);
  };
  const auto [first, errors, hits] = run();
  const auto [second, errors2, hits2] = run();
  EXPECT_EQ(first, second);
  EXPECT_GT(hits, 0u);
  EXPECT_EQ(hits, hits2);
  EXPECT_GE(errors, hits);  // every hit is an error the nodes report
}

}  // namespace
}  // namespace canemu
