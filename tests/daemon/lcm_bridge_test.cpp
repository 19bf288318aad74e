// The LCM bridge on LCM's memq:// provider: one LCM instance inside this process, so the test
// publishes on the bridge's TX channel and subscribes to its other channels on the bridge's own
// instance (lcm_instance()); what LCM delivers is handled when the bridge is kicked, as canemud
// does when the instance's descriptor is readable. The same bridge runs over udpm:// between
// processes in tests/python/test_lcm_bridge.py. What every bridge does is bridge_contract.hpp's,
// run here as LcmBridge/BridgeContract, and message_bridge_contract.hpp's as
// LcmBridge/MessageBridges.
#include "canemu/daemon/bridges/lcm_bridge.hpp"

#include <lcm/lcm.h>

#include <deque>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "bridge_contract.hpp"
#include "bridge_test_support.hpp"
#include "canemu/daemon/world/simulation.hpp"
#include "canemu/daemon/world/status.hpp"
#include "canemu_lcm/error_t.hpp"
#include "canemu_lcm/frame_t.hpp"
#include "canemu_lcm/state_t.hpp"
#include "message_bridge_contract.hpp"

namespace canemu::daemon {
namespace {

using namespace bridge_test;
using namespace daemon_test;

BridgeConfig lcm_bridge(const std::string& bus, uint32_t restart_ms = 0) {
  BridgeConfig b;
  b.kind = "lcm";
  b.bus = bus;
  b.url = "memq://";
  b.restart_ms = restart_ms;
  return b;
}

// Everything published on one channel, decoded with the C++ types programs use.
template <class T>
struct Recorded {
  std::vector<T> messages;
  Recorded(lcm_t* lcm, const std::string& channel) {
    lcm_subscribe(lcm, channel.c_str(), &Recorded::handle, this);
  }
  static void handle(const lcm_recv_buf_t* rbuf, const char*, void* user) {
    T m;
    ASSERT_GE(m.decode(rbuf->data, 0, static_cast<int>(rbuf->data_size)), 0);
    static_cast<Recorded*>(user)->messages.push_back(m);
  }
};

void publish(lcm_t* lcm, const std::string& channel, const canemu_lcm::frame_t& f) {
  std::vector<uint8_t> bytes(static_cast<std::size_t>(f.getEncodedSize()));
  ASSERT_EQ(f.encode(bytes.data(), 0, static_cast<int>(bytes.size())),
            static_cast<int>(bytes.size()));
  ASSERT_EQ(lcm_publish(lcm, channel.c_str(), bytes.data(), static_cast<unsigned>(bytes.size())),
            0);
}

// The contract's adapter (bridge_contract.hpp): the bridge's channels on its own LCM instance.
struct LcmAdapter {
  lcm_t* lcm = nullptr;  // the first bridge's, with its channels recorded
  std::string prefix;    // its channels' names begin so
  std::unique_ptr<Recorded<canemu_lcm::frame_t>> frames;
  std::unique_ptr<Recorded<canemu_lcm::error_t>> error_log;
  std::unique_ptr<Recorded<canemu_lcm::state_t>> state_log;
  static constexpr TransportTraits kTraits{"lcm", ipc::kBridgeLcm, true, "LCM bridge of can0",
                                           "lcm:can0"};

  void configure(BridgeConfig& b, const std::string& channels_of) {
    b.url = "memq://";
    if (channels_of != b.bus) {
      b.channel_prefix = default_lcm_prefix(channels_of);
    }
  }
  // The bridge's own LCM instance, with the channels it publishes on recorded.
  void attach(Bridge& bridge) {
    lcm = lcm_instance(bridge.transport());
    ASSERT_NE(lcm, nullptr);
    prefix = bridge.options().channel_prefix;
    EXPECT_EQ(prefix, default_lcm_prefix(bridge.options().bus));
    frames = std::make_unique<Recorded<canemu_lcm::frame_t>>(lcm, channel("FRAMES"));
    error_log = std::make_unique<Recorded<canemu_lcm::error_t>>(lcm, channel("ERRORS"));
    state_log = std::make_unique<Recorded<canemu_lcm::state_t>>(lcm, channel("STATES"));
  }
  std::string channel(const char* name) const { return prefix + name; }
  bool remove(Simulation& sim, const std::string& bus) {
    return sim.remove_bus_bridge(BridgeKind::lcm, bus);
  }
  void inject(const std::string& cansend) {
    publish(lcm, channel("TX"), published<canemu_lcm::frame_t>(cansend));
  }
  std::size_t inject_what_is_no_frame() {
    canemu_lcm::frame_t disagree = published<canemu_lcm::frame_t>("100#0102");
    disagree.len = 3;  // its DLC says 2 bytes
    publish(lcm, channel("TX"), disagree);
    publish(lcm, channel("TX"),
            published<canemu_lcm::frame_t>("800#"));  // 12 bits in a standard identifier
    canemu_lcm::state_t other{};                      // another type altogether
    std::vector<uint8_t> bytes(static_cast<std::size_t>(other.getEncodedSize()));
    other.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
    lcm_publish(lcm, channel("TX").c_str(), bytes.data(), static_cast<unsigned>(bytes.size()));
    const uint8_t junk[3] = {1, 2, 3};
    lcm_publish(lcm, channel("TX").c_str(), junk, sizeof junk);
    publish(lcm, channel("TXX"),
            published<canemu_lcm::frame_t>("001#"));  // another channel: not the bridge's
    return 4;
  }
  // What LCM has for the bridge is handled when it is kicked (its descriptor was readable); so
  // is what it published for the test's subscriptions.
  void deliver(Bridge& bridge, std::size_t) { bridge.kick(); }
  std::vector<std::string> seen(Bridge& bridge, std::size_t) {
    bridge.kick();
    return converted(frames->messages, seen_text<canemu_lcm::frame_t>);
  }
  std::vector<PublishedError> errors(Bridge& bridge, std::size_t) {
    bridge.kick();
    return converted(error_log->messages, published_error<canemu_lcm::error_t>);
  }
  std::vector<std::string> states(Bridge& bridge, std::size_t, bool with_tec = false) {
    bridge.kick();
    return converted(state_log->messages,
                     [&](const canemu_lcm::state_t& s) { return published_state(s, with_tec); });
  }
  std::string listing() const { return "interface= url=memq:// prefix=CANEMU_CAN0_"; }
  std::string second_bridge_error() const { return "can0 has an LCM bridge already"; }
  std::string loop_error() const {
    return "the LCM bridge of can0 uses the channels CANEMU_CAN0_* on memq:// already (their "
           "frames would loop)";
  }
};

TEST(LcmBridge, ChannelNamesAndTheirChecks) {
  EXPECT_EQ(default_lcm_prefix("can0"), "CANEMU_CAN0_");
  EXPECT_EQ(default_lcm_prefix("fd-1.x"), "CANEMU_FD_1_X_");
  EXPECT_EQ(lcm_prefix_problem("ROBOT/CAN0."), std::nullopt);
  EXPECT_EQ(lcm_prefix_problem("A B"),
            "\"A B\" is not a channel prefix (letters, digits, '_', '-', '.', '/')");
  EXPECT_EQ(lcm_prefix_problem(""), "\"\" is not a channel prefix (1 to 63 characters)");
  EXPECT_EQ(lcm_url_problem("udpm://239.255.76.67:7667?ttl=0"), std::nullopt);
  EXPECT_EQ(lcm_url_problem("239.255.76.67"),
            "\"239.255.76.67\" is not an LCM URL (provider://network?options, up to 127 "
            "characters)");
  EXPECT_TRUE(lcm_available());
}

TEST(LcmBridgeConfig, ReadsTheTableWithItsDefaultsAndNamesEveryMistake) {
  const Config cfg = config_of(kTwoBuses + bridge_table("lcm", "can0") +
                               bridge_table("lcm", "can1",
                                            "restart_ms = 100\n"
                                            "url = \"udpm://239.255.76.67:7668?ttl=0\"\n"
                                            "channel_prefix = \"ROBOT/CAN1_\"\n"));
  ASSERT_EQ(cfg.bridges.size(), 2u);
  EXPECT_EQ(cfg.bridges[0].kind, "lcm");
  EXPECT_EQ(cfg.bridges[0].url, "udpm://239.255.76.67:7667?ttl=0");
  EXPECT_EQ(cfg.bridges[0].channel_prefix, "CANEMU_CAN0_");
  EXPECT_EQ(cfg.bridges[1].url, "udpm://239.255.76.67:7668?ttl=0");
  EXPECT_EQ(cfg.bridges[1].channel_prefix, "ROBOT/CAN1_");
  EXPECT_EQ(cfg.bridges[1].restart_ms, 100u);
  EXPECT_EQ(
      config_errors(kTwoBuses + bridge_table("lcm", "can0", "interface = \"vcan0\"\n") +
                    bridge_table("lcm", "can0", "channel_prefix = \"A B\"\nurl = \"nowhere\"\n") +
                    bridge_table("lcm", "can1", "channel_prefix = \"CANEMU_CAN0_\"\n")),
      (std::vector<std::string>{
          "t.toml:8:1: bridge[0].interface: unknown key (known here: kind, bus, url, "
          "channel_prefix, restart_ms)",
          "t.toml:11:7: bridge[1].bus: another LCM bridge joins \"can0\" already",
          "t.toml:13:7: bridge[1].url: \"nowhere\" is not an LCM URL "
          "(provider://network?options, up to 127 characters)",
          "t.toml:12:18: bridge[1].channel_prefix: \"A B\" is not a channel prefix "
          "(letters, digits, '_', '-', '.', '/')",
          "t.toml:14:1: bridge[2]: another LCM bridge uses the channels CANEMU_CAN0_* on "
          "udpm://239.255.76.67:7667?ttl=0 already (their frames would loop)"}));
}

TEST(LcmBridge, AUrlLcmCannotOpenIsRefused) {
  auto sim = world(kTwoBuses);
  BridgeConfig bad = lcm_bridge("can1");
  bad.url = "nosuch://";
  EXPECT_EQ(error_text(sim->add_bridge(bad)), "LCM cannot open \"nosuch://\"");
  ASSERT_TRUE(sim->add_bridge(lcm_bridge("can0")));
  EXPECT_FALSE(sim->remove_bridge("can0"));  // a SocketCAN bridge's interface: none
  EXPECT_EQ(sim->bridges().size(), 1u);
}

// The C++ types programs use and the C types canemud uses are the same messages.
TEST(LcmTypes, CppAndCAgreeOnTheWire) {
  canemu_lcm::frame_t f = published<canemu_lcm::frame_t>("1ABCDEF0#090807");
  f.timestamp_ns = 123'456'789;
  f.from_tx = true;
  std::vector<uint8_t> bytes(static_cast<std::size_t>(f.getEncodedSize()));
  ASSERT_EQ(f.encode(bytes.data(), 0, static_cast<int>(bytes.size())),
            static_cast<int>(bytes.size()));
  EXPECT_EQ(bytes.size(), 8u + 8 + 4 + 7 + 64 + 1);  // fingerprint and fields, big-endian
  EXPECT_EQ(bytes[8 + 7], 0x15);                     // 123456789 = 0x075BCD15
  EXPECT_EQ(bytes[16], 0x1A);
}

// The contract (bridge_contract.hpp) through this transport.
INSTANTIATE_TYPED_TEST_SUITE_P(LcmBridge, BridgeContract, LcmAdapter);
INSTANTIATE_TYPED_TEST_SUITE_P(LcmBridge, MessageBridges, LcmAdapter);

}  // namespace
}  // namespace canemu::daemon
