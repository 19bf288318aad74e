// The SocketCAN bridge on the host: the interface is played by one end of a SOCK_SEQPACKET pair
// (whole frames per packet, as a CAN_RAW socket gives them), the kernel's programs by the other.
// This machine's kernel has no CAN modules; the same bridge runs against vcan in tests/guest/.
// What every bridge does is bridge_contract.hpp's, run here as SocketCanBridge/BridgeContract.
#include "canemu/daemon/bridges/socketcan_bridge.hpp"

#include <linux/can.h>
#include <linux/can/error.h>
#include <linux/filter.h>
#include <linux/seccomp.h>
#include <sys/prctl.h>
#include <sys/socket.h>
#include <sys/syscall.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstddef>
#include <cstring>
#include <deque>
#include <fstream>
#include <iterator>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "bridge_contract.hpp"
#include "bridge_test_support.hpp"
#include "canemu/daemon/base/channel.hpp"
#include "canemu/daemon/base/log.hpp"
#include "canemu/daemon/config/scenario.hpp"
#include "canemu/daemon/world/simulation.hpp"
#include "canemu/daemon/world/status.hpp"
#include "canemu/ipc/socketcan.hpp"

namespace canemu::daemon {
namespace {

using namespace bridge_test;
using namespace daemon_test;

// The kernel side: what programs write on the interface and what they read from it.
struct Interface {
  ipc::UniqueFd kernel;
  ipc::UniqueFd bridge;
  Interface() {
    int fds[2];
    EXPECT_EQ(::socketpair(AF_UNIX, SOCK_SEQPACKET | SOCK_NONBLOCK | SOCK_CLOEXEC, 0, fds), 0);
    kernel.reset(fds[0]);
    bridge.reset(fds[1]);
  }
  void write_frame(const ipc::socketcan::Frame& f) {
    const auto bytes = ipc::socketcan::to_struct(f);
    EXPECT_EQ(::send(kernel.get(), bytes.data(), bytes.size(), 0),
              static_cast<ssize_t>(bytes.size()));
  }
  void write_text(const std::string& cansend) { write_frame(cansend_frame(cansend)); }
  // Everything the bridge wrote, as candump would print it.
  std::vector<std::string> read_all() {
    std::vector<std::string> out;
    uint8_t buf[128];
    ssize_t n;
    while ((n = ::recv(kernel.get(), buf, sizeof buf, 0)) > 0) {
      const auto f = ipc::socketcan::from_struct(buf, static_cast<std::size_t>(n));
      out.push_back(f ? ipc::socketcan::candump_text(*f) : "(" + std::to_string(n) + " bytes)");
    }
    return out;
  }
};

void run_for(Simulation& sim, int64_t ns) {
  sim.scheduler().run_until(sim.scheduler().now() + model::SimDuration(ns));
}

// A simulation with the bridge of one bus on vcan0, the kernel's end of vcan0, and a node on
// the bus beside the bridge's.
class SocketCanBridge : public ::testing::Test {
 protected:
  std::unique_ptr<Simulation> simulation;
  Interface vcan;
  Bridge* bridged = nullptr;
  std::unique_ptr<BusNode> ecu;

  void open(const char* config, const std::string& bus, bool error_frames, uint32_t restart_ms) {
    simulation = world(config);
    auto b = simulation->add_bridge({"socketcan", bus, "vcan0", error_frames, restart_ms},
                                    std::move(vcan.bridge));
    ASSERT_TRUE(b) << error_text(b);
    bridged = *b;
    ecu = std::make_unique<BusNode>(*simulation, 0);
  }
};

// The contract's adapter (bridge_contract.hpp): the bridge of bus B on the interface "vB"
// ("vcan0" for can0), with error frames; the frames the kernel's programs write and read.
struct SocketCanAdapter {
  std::deque<Interface> interfaces;  // the first is can0's
  static constexpr TransportTraits kTraits{"socketcan", ipc::kBridgeSocketCan, false,
                                           "bridge on vcan0", "socketcan:vcan0"};

  void configure(BridgeConfig& b, const std::string& channels_of) {
    b.interface = "v" + channels_of;
    b.error_frames = true;
  }
  // The bridge's end of a new interface.
  ipc::UniqueFd port() { return std::move(interfaces.emplace_back().bridge); }
  bool remove(Simulation& sim, const std::string& bus) { return sim.remove_bridge("v" + bus); }
  void inject(const std::string& cansend) { interfaces.front().write_text(cansend); }
  std::size_t inject_what_is_no_frame() {
    ipc::socketcan::Frame err;  // an error frame: what a controller saw, nothing to send
    err.can_id = CAN_ERR_FLAG | CAN_ERR_BUSOFF;
    err.len = 8;
    interfaces.front().write_frame(err);
    const char junk[5] = {1, 2, 3, 4, 5};  // neither a can_frame nor a canfd_frame
    EXPECT_EQ(::send(interfaces.front().kernel.get(), junk, sizeof junk, 0), 5);
    return 2;
  }
  void deliver(Bridge& bridge, std::size_t) { bridge.kick(); }  // the socket was readable
  std::vector<std::string> seen(Bridge&, std::size_t) { return interfaces.front().read_all(); }
  // The error frames Linux's CAN drivers write for bus-off, the restart and error-active again.
  std::vector<std::string> states(Bridge&, std::size_t) {
    std::vector<std::string> told;
    for (const std::string& f : interfaces.front().read_all()) {
      told.push_back(f == "20000240#000000000000FF00"   ? "bus-off"
                     : f == "20000100#0000000000000000" ? "restarted"
                     : f == "20000204#0040000000000000" ? "error-active"
                                                        : f);
    }
    return told;
  }
  std::string listing() const { return "interface=vcan0 url= prefix="; }
  std::string loop_error() const {
    return "vcan0 is bridged to can0 already (its frames would loop)";
  }
};

// What the bridge makes of each read from the interface, for a classic and a CAN FD bus: the
// frame, or the frame and the rule it breaks.
TEST_F(SocketCanBridge, EachReadFromTheInterfaceIsAFrameOrARejectionWithItsReason) {
  const auto read = [](const ipc::socketcan::Frame& f, bool fd_bus, uint8_t raw_len = 0xFF) {
    auto bytes = ipc::socketcan::to_struct(f);
    if (raw_len != 0xFF) {
      bytes[4] = raw_len;  // what a program may write, beyond what a Frame holds
    }
    return frame_from_interface(bytes.data(), bytes.size(), fd_bus);
  };
  const auto fd = cansend_frame("123##1AABB");
  EXPECT_EQ(read(fd, false).error().detail,
            "the CAN FD frame 123##1AABB (the bus is a classic CAN bus)");
  EXPECT_EQ(read(fd, false).error().why, BridgeReject::fd_on_classic);
  ASSERT_TRUE(read(fd, true));
  EXPECT_EQ(read(fd, true)->dlc, 2);
  ipc::socketcan::Frame err;
  err.can_id = CAN_ERR_FLAG | CAN_ERR_PROT | CAN_ERR_BUSERROR;
  err.len = 8;
  err.data[2] = CAN_ERR_PROT_BIT;
  const std::string err_reason =
      "the error frame 20000088#0000010000000000 (an error frame reports what a controller saw; "
      "it is no frame to send on a bus)";
  EXPECT_EQ(read(err, false).error().detail, err_reason);
  EXPECT_EQ(read(err, true).error().detail, err_reason);
  EXPECT_EQ(read(err, true).error().why, BridgeReject::error_frame);
  const uint8_t junk[5] = {1, 2, 3, 4, 5};
  EXPECT_EQ(frame_from_interface(junk, sizeof junk, false).error().detail,
            "a read of 5 bytes, neither a struct can_frame (16) nor a canfd_frame (72)");
  EXPECT_EQ(frame_from_interface(junk, sizeof junk, false).error().why, BridgeReject::not_a_frame);
  auto classic = cansend_frame("123#0102030405060708");
  EXPECT_EQ(read(classic, false, 9).error().detail,
            "123#0102030405060708 (its length 9 is above 8)");
  EXPECT_EQ(read(classic, false, 9).error().why, BridgeReject::bad_fields);
  auto long_fd = cansend_frame("123##1AABB");
  EXPECT_EQ(read(long_fd, true, 65).error().detail.substr(0, 10), "123##1AABB");
  EXPECT_NE(read(long_fd, true, 65).error().detail.find("(its length 65 is above 64)"),
            std::string::npos);
  auto remote_fd = fd;
  remote_fd.can_id |= CAN_RTR_FLAG;
  EXPECT_EQ(read(remote_fd, true).error().detail, "123##1AABB (CAN FD has no remote frames)");
  // A CAN FD length between two DLCs' lengths: the next DLC, zeros up to its length.
  auto odd = cansend_frame("123##101020304050607080910111213");  // 13 bytes
  odd.data[13] = 0x77;
  const auto padded = read(odd, true);
  ASSERT_TRUE(padded) << padded.error().detail;
  EXPECT_EQ(padded->dlc, 10);  // 16 bytes
  EXPECT_EQ(padded->data[12], 0x13);
  EXPECT_EQ(padded->data[13], 0);
}

// Rejections are counted by reason, kept with the last one's details, and logged with the
// reason, at most RejectLog's burst of lines in its window (wall-clock: the journal's concern).
TEST_F(SocketCanBridge, RejectionsAreCountedByReasonAndLoggedRateLimited) {
  open(kClassic, "can0", false, 0);
  log::Capture log;
  run_to(*simulation, 1'000'000);
  vcan.write_text("123##1AABB");  // CAN FD on a classic bus
  ipc::socketcan::Frame err;
  err.can_id = CAN_ERR_FLAG | CAN_ERR_BUSOFF;
  err.len = 8;
  vcan.write_frame(err);
  for (int i = 0; i < 5; ++i) {
    vcan.write_text("124##0");
  }
  vcan.write_text("125#01");  // a frame: sent
  bridged->kick();
  run_to(*simulation, 2'000'000);
  EXPECT_EQ(bridged->stats().rejected, 7u);
  EXPECT_EQ(bridged->stats().received, 8u);
  EXPECT_EQ(ecu->texts, (std::vector<std::string>{"125#01"}));
  const auto& r = bridged->rejections();
  EXPECT_EQ(r.count(static_cast<std::size_t>(BridgeReject::fd_on_classic)), 6u);
  EXPECT_EQ(r.count(static_cast<std::size_t>(BridgeReject::error_frame)), 1u);
  EXPECT_EQ(r.last(), "rejected the CAN FD frame 124##0 (the bus is a classic CAN bus)");
  const auto lines = log.lines();
  ASSERT_EQ(lines.size(), static_cast<std::size_t>(RejectLog<kBridgeRejectReasons>::kBurst));
  EXPECT_EQ(lines[0],
            "<4>canemud: bridge on vcan0: rejected the CAN FD frame 123##1AABB (the bus is a "
            "classic CAN bus)");
  EXPECT_EQ(lines[1],
            "<4>canemud: bridge on vcan0: rejected the error frame 20000040#0000000000000000 (an "
            "error frame reports what a controller saw; it is no frame to send on a bus)");
}

// A CAN FD bus on an interface whose MTU is not CANFD_MTU: a warning with the way out.
TEST_F(SocketCanBridge, AnFdBusOnAClassicMtuInterfaceIsWarnedAbout) {
  EXPECT_EQ(mtu_warning("vcan0", "fd0", true, 16),
            "vcan0 has MTU 16, not 72 (CAN FD): the CAN FD frames of fd0 cannot be written to "
            "it (counted as IF-DROP) and programs cannot send CAN FD frames on it; classic frames "
            "pass. For CAN FD: ip link set vcan0 down; ip link set vcan0 mtu 72 up");
  EXPECT_EQ(mtu_warning("vcan0", "fd0", true, 72), std::nullopt);
  EXPECT_EQ(mtu_warning("vcan0", "can0", false, 16), std::nullopt);
  EXPECT_EQ(mtu_warning("vcan0", "can0", false, 72), std::nullopt);  // FD frames: rejected
}

TEST_F(SocketCanBridge, AFullQueueDropsAndCountsWhatTheBusCouldNotTake) {
  open(kClassic, "can0", false, 0);
  // 1100 frames written at one instant: the first goes on the wire, 1024 wait, the rest drop.
  for (int i = 0; i < 1100; ++i) {
    vcan.write_text("100#");
    if (i % 100 == 99) {
      bridged->kick();  // the socket pair holds a few hundred packets; read as the loop would
    }
  }
  for (int i = 0; i < 8; ++i) {
    bridged->kick();
  }
  EXPECT_EQ(bridged->stats().queue_dropped, 1100u - 1 - 1024);
  run_for(*simulation, 1'000'000'000);
  EXPECT_EQ(bridged->stats().from_interface, 1025u);
  EXPECT_EQ(ecu->texts.size(), 1025u);
}

TEST_F(SocketCanBridge, ErrorFramesOnlyWhenAskedFor) {
  auto sim = world(kClassic);
  Interface quiet;
  Interface loud;
  // Two bridges of one bus on two interfaces, one with error frames. A node at 250 kbit/s on
  // the 500 kbit/s bus makes errors that both bridges' nodes detect.
  ASSERT_TRUE(sim->add_bridge({"socketcan", "can0", "vcan0", false, 0}, std::move(quiet.bridge)));
  auto b = sim->add_bridge({"socketcan", "can0", "vcan1", true, 0}, std::move(loud.bridge));
  ASSERT_TRUE(b);
  model::HostedNode& wrong = sim->spare_node(0);
  const auto slow = node_timing(false, {250'000, 0, 875});
  bool sent = false;
  wrong.start(*slow, nullptr, [&]() -> std::optional<model::TxFrame> {
    if (sent) {
      return std::nullopt;
    }
    sent = true;
    model::FrameSpec spec;
    spec.id = 0x100;
    return model::TxFrame{*model::Frame::create(spec), true};
  });
  wrong.kick();
  run_for(*sim, 2'000'000);
  EXPECT_TRUE(quiet.read_all().empty());
  const auto errors = loud.read_all();
  ASSERT_FALSE(errors.empty());
  for (const std::string& e : errors) {
    EXPECT_EQ(e.substr(0, 3), "200") << e;  // CAN_ERR_FLAG
    EXPECT_EQ(e.size(), 8u + 1 + 16) << e;  // 8 data bytes
  }
  EXPECT_EQ((*b)->stats().error_frames, errors.size());
}

// A CRC error is flagged where ISO 11898-1 has the receiver flag it, after the ACK delimiter
// (the receiver finds the mismatch in the CRC sequence but starts its error flag at the bit
// after the ACK delimiter): the SJA1000's error code capture records that segment (0x1B), and
// the error frame carries it in data[3] as CAN_ERR_PROT_LOC_ACK_DEL, as Linux's sja1000 driver
// copies it. docs/socketcan.md's error frame table says the same.
TEST_F(SocketCanBridge, ACrcErrorFrameCarriesTheAckDelimiterAsItsLocation) {
  open(kClassic, "can0", true, 0);
  apply_scenario(*simulation,
                 "[[fault]]\nat = \"0s\"\nbus = \"can0\"\nmatch = { id = 0x321 }\neffect = "
                 "\"crc_error\"\ncount = 1\n");
  ecu->send("321#AB");
  run_for(*simulation, 2'000'000);
  const std::vector<std::string> written = vcan.read_all();
  ASSERT_GE(written.size(), 2u);
  // The error frame (a receiver's CRC error: no type bits, not transmitting), then the frame's
  // retransmission.
  const std::string& crc = written.front();
  EXPECT_EQ(crc.substr(0, 9), "20000288#") << crc;
  EXPECT_EQ(crc.substr(9 + 2 * 2, 4), fmt::format("{:02X}{:02X}", 0, CAN_ERR_PROT_LOC_ACK_DEL))
      << crc;
  EXPECT_EQ(CAN_ERR_PROT_LOC_ACK_DEL, 0x1B);
  EXPECT_EQ(written.back(), "321#AB");
  std::ifstream docs(std::string(CANEMU_SOURCE_DIR) + "/docs/socketcan.md");
  std::string line, row;
  while (std::getline(docs, line)) {
    if (line.starts_with("| CRC error |")) {
      row = line;
    }
  }
  EXPECT_NE(row.find("`data[3]` `CAN_ERR_PROT_LOC_ACK_DEL` (0x1B)"), std::string::npos) << row;
  EXPECT_EQ(row.find("CRC_SEQ"), std::string::npos) << row;
}

// ---- restarts after bus-off

TEST_F(SocketCanBridge, TheCanFdControllerRestartsTheSameWay) {
  open(kFd, "fd0", false, 2);  // 500 kbit/s arbitration: the same recovery time
  const model::FaultConfinement& fc = bridged->node().controller().confinement();
  bus_off_at(*simulation, bridged->node(), 500'000);
  run_to(*simulation, 2'500'000 - 1);
  EXPECT_EQ(bridged->stats().restarts, 0u);
  run_to(*simulation, 2'500'000);
  EXPECT_EQ(bridged->stats().restarts, 1u);
  run_to(*simulation, 2'500'000 + kRecoveryNs - 1);
  EXPECT_TRUE(fc.bus_off());
  run_to(*simulation, 2'500'000 + kRecoveryNs);
  EXPECT_FALSE(fc.bus_off());
}

TEST_F(SocketCanBridge, WithoutRestartMsTheNodeStaysBusOffUntilRestartedByHand) {
  open(kClassic, "can0", false, 0);
  Bridge& bridge = *bridged;
  const model::FaultConfinement& fc = bridge.node().controller().confinement();
  EXPECT_EQ(error_text(bridge.restart()),
            "bridge on vcan0 is error-active, not bus-off: nothing to restart");
  bus_off_at(*simulation, bridge.node(), 1'000'000);
  run_to(*simulation, 1'000'000'000);  // a second: still bus-off
  EXPECT_TRUE(fc.bus_off());
  EXPECT_FALSE(fc.recovering());
  EXPECT_TRUE(bridge.restart());
  EXPECT_EQ(bridge.stats().restarts, 1u);
  EXPECT_EQ(error_text(bridge.restart()),
            "bridge on vcan0 restarts already (waits for 128 x 11 recessive bits, 128 left)");
  EXPECT_EQ(bridge.stats().restarts, 1u);
  run_to(*simulation, 1'000'000'000 + kRecoveryNs);
  EXPECT_FALSE(fc.bus_off());
  EXPECT_TRUE(vcan.read_all().empty());  // no error frames asked for
  ipc::BridgeListReply list{};
  fill_bridge_list(*simulation, list);
  ASSERT_EQ(list.count, 1);
  EXPECT_EQ(list.bridges[0].restarts, 1u);
  EXPECT_EQ(list.bridges[0].restart_ms, 0u);
}

TEST_F(SocketCanBridge, ARestartByHandBeforeTheTimerCountsOnce) {
  open(kClassic, "can0", false, 100);
  Bridge& bridge = *bridged;
  bus_off_at(*simulation, bridge.node(), 1'000'000);
  run_to(*simulation, 2'000'000);
  EXPECT_TRUE(bridge.restart());
  run_to(*simulation, 200'000'000);  // past the timer's 101 ms
  EXPECT_EQ(bridge.stats().restarts, 1u);
  EXPECT_FALSE(bridge.node().controller().confinement().bus_off());
  // Removing a bridge whose timer is due cancels it.
  bus_off_at(*simulation, bridge.node(), 300'000'000);
  run_to(*simulation, 301'000'000);
  EXPECT_TRUE(simulation->remove_bridge("vcan0"));
  run_to(*simulation, 500'000'000);
}

// A real way there: a fault rule gives every transmission of 123h a bit error, 32 of them take
// the bridge's node from TEC 0 to 256 (8 each), and restart_ms later the node restarts,
// recovers and sends the frame its transmit buffer kept (the SJA1000 keeps a request through
// bus-off) and what waited in the bridge's queue.
TEST_F(SocketCanBridge, BitErrorsDriveTheNodeBusOffAndItRestartsAfterRestartMs) {
  open(kClassic, "can0", true, 20);
  apply_scenario(*simulation,
                 "[[fault]]\nat = \"0s\"\nbus = \"can0\"\nmatch = { id = 0x123 }\neffect = "
                 "\"bit_error\"\ncount = 32\n");
  Bridge& bridge = *bridged;
  vcan.write_text("123#01");
  vcan.write_text("124#02");
  bridge.kick();
  const model::FaultConfinement& fc = bridge.node().controller().confinement();
  // In steps of 1 us: the step that sees bus-off, and the one that sees the restart, which
  // must be exactly 20 ms (20000 steps) later.
  int64_t step = 0;
  while (!fc.bus_off() && step < 100'000) {
    run_to(*simulation, ++step * 1'000);
  }
  ASSERT_TRUE(fc.bus_off());
  const int64_t bus_off_step = step;
  EXPECT_TRUE(ecu->texts.empty());
  while (bridge.stats().restarts == 0 && step < bus_off_step + 100'000) {
    run_to(*simulation, ++step * 1'000);
  }
  EXPECT_EQ(step, bus_off_step + 20'000);
  run_to(*simulation, step * 1'000 + kRecoveryNs + 1'000'000);
  EXPECT_FALSE(fc.bus_off());
  EXPECT_EQ(ecu->texts, (std::vector<std::string>{"123#01", "124#02"}));
  EXPECT_EQ(bridge.stats().from_interface, 2u);
  EXPECT_EQ(bridge.stats().tx_failed, 0u);
  const std::vector<std::string> errors = vcan.read_all();
  ASSERT_GE(errors.size(), 3u);
  EXPECT_EQ(std::vector<std::string>(errors.end() - 3, errors.end()),
            (std::vector<std::string>{"20000240#000000000000FF00", "20000100#0000000000000000",
                                      "20000204#0040000000000000"}));
  EXPECT_EQ(std::count(errors.begin(), errors.end(), "20000100#0000000000000000"), 1);
  EXPECT_EQ(bridge.stats().restarts, 1u);
}

TEST_F(SocketCanBridge, WithoutCanModulesTheInterfaceCannotBeOpenedAndSaysWhy) {
  auto port = open_can_raw("vcan-none");
  ASSERT_FALSE(port);
  // Either the kernel has no CAN (socket fails) or the interface does not exist.
  EXPECT_EQ(port.error().text.substr(0, 11), "vcan-none: ") << port.error();
  EXPECT_EQ(open_can_raw("a-name-that-is-too-long").error(),
            "\"a-name-that-is-too-long\" is not an interface name (1 to 15 characters)");
}

// socket() of any family but AF_UNIX fails with EAFNOSUPPORT from now on, as in canemud.service
// as shipped (RestrictAddressFamilies=AF_UNIX installs such a seccomp filter).
void refuse_every_family_but_unix() {
  sock_filter filter[] = {
      BPF_STMT(BPF_LD | BPF_W | BPF_ABS, offsetof(seccomp_data, nr)),
      BPF_JUMP(BPF_JMP | BPF_JEQ | BPF_K, __NR_socket, 0, 3),
      BPF_STMT(BPF_LD | BPF_W | BPF_ABS, offsetof(seccomp_data, args[0])),
      BPF_JUMP(BPF_JMP | BPF_JEQ | BPF_K, AF_UNIX, 1, 0),
      BPF_STMT(BPF_RET | BPF_K, SECCOMP_RET_ERRNO | EAFNOSUPPORT),
      BPF_STMT(BPF_RET | BPF_K, SECCOMP_RET_ALLOW),
  };
  sock_fprog program{static_cast<unsigned short>(std::size(filter)), filter};
  if (::prctl(PR_SET_NO_NEW_PRIVS, 1, 0, 0, 0) != 0 ||
      ::prctl(PR_SET_SECCOMP, SECCOMP_MODE_FILTER, &program) != 0) {
    ::_exit(2);
  }
}

TEST_F(SocketCanBridge, ABridgeWhoseAddressFamilyIsRefusedNamesTheDropInThatAllowsIt) {
  EXPECT_TRUE(refused_family(AF_INET));  // this machine allows IP sockets
  int out[2];
  ASSERT_EQ(::pipe(out), 0);
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {  // no gtest here: what the child found goes through the pipe
    refuse_every_family_but_unix();
    auto sim = world(kClassic);
    BridgeConfig lcm;
    lcm.kind = "lcm";
    lcm.bus = "can0";
    BridgeConfig dds = lcm;
    dds.kind = "dds";
    const std::string found = std::string(!refused_family(AF_UNIX) ? "AF_UNIX refused" : "-") +
                              "\n" + error_text(open_can_raw("vcan0")) + "\n" +
                              error_text(sim->add_bridge(lcm)) + "\n" +
                              error_text(sim->add_bridge(dds));
    const bool written =
        ::write(out[1], found.data(), found.size()) == static_cast<ssize_t>(found.size());
    ::_exit(written ? 0 : 3);
  }
  ::close(out[1]);
  std::string found;
  char buffer[512];
  for (ssize_t n; (n = ::read(out[0], buffer, sizeof buffer)) > 0;) {
    found.append(buffer, static_cast<std::size_t>(n));
  }
  ::close(out[0]);
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << status;
  EXPECT_EQ(found,
            "-\n"
            "vcan0: AF_CAN refused (no CAN in the kernel, or no drop-in socketcan.conf)\n"
            "LCM bridge of can0: AF_INET refused (no drop-in ip.conf)\n"
            "DDS bridge of can0: AF_INET refused (no drop-in ip.conf)");
}

TEST(BridgeConfig, ReadsTheTableAndNamesEveryMistake) {
  const Config cfg = config_of(
      kClassic + bridge_table("socketcan", "can0", "interface = \"vcan0\"\nerror_frames = true\n"));
  ASSERT_EQ(cfg.bridges.size(), 1u);
  EXPECT_EQ(cfg.bridges[0].interface, "vcan0");
  EXPECT_TRUE(cfg.bridges[0].error_frames);
  EXPECT_EQ(cfg.bridges[0].restart_ms, 0u);
  const Config restarting = config_of(
      kClassic + bridge_table("socketcan", "can0", "interface = \"vcan0\"\nrestart_ms = 100\n"));
  ASSERT_EQ(restarting.bridges.size(), 1u);
  EXPECT_EQ(restarting.bridges[0].restart_ms, 100u);
  EXPECT_EQ(
      config_errors(
          kClassic + bridge_table("socketcan", "can0", "interface = \"vcan0\"\nrestart_ms = -1\n") +
          bridge_table("socketcan", "can0", "interface = \"vcan1\"\nrestart_ms = 60001\n") +
          bridge_table("socketcan", "can0", "interface = \"vcan2\"\nrestart_ms = \"100ms\"\n")),
      (std::vector<std::string>{"t.toml:7:14: bridge[0].restart_ms: -1 is outside 0..60000",
                                "t.toml:12:14: bridge[1].restart_ms: 60001 is outside 0..60000",
                                "t.toml:17:14: bridge[2].restart_ms: must be an integer"}));
  EXPECT_EQ(config_errors(kClassic + bridge_table("zmq", "can9", "interface = \"vcan0\"\n") +
                          bridge_table("socketcan", "can0", "interface = \"vcan0\"\nloop = 1\n")),
            (std::vector<std::string>{
                "t.toml:4:8: bridge[0].kind: \"zmq\" is not a bridge kind (socketcan, lcm, dds)",
                "t.toml:5:7: bridge[0].bus: no bus is named \"can9\"",
                "t.toml:11:1: bridge[1].loop: unknown key (known here: kind, bus, interface, "
                "error_frames, restart_ms)",
                "t.toml:10:13: bridge[1].interface: another bridge uses \"vcan0\" already (its "
                "frames would loop)"}));
}

// The contract (bridge_contract.hpp) through this transport.
INSTANTIATE_TYPED_TEST_SUITE_P(SocketCanBridge, BridgeContract, SocketCanAdapter);

}  // namespace
}  // namespace canemu::daemon
