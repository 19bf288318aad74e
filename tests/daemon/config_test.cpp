#include "canemu/daemon/config/config.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <fstream>
#include <optional>

#include <fmt/format.h>

#include "../support/many_buses.hpp"
#include "../support/temp_dir.hpp"
#include "canemu/daemon/config/scenario.hpp"
#include "daemon_test_support.hpp"

namespace canemu::daemon {
namespace {

using daemon_test::config_errors;

TEST(Config, EmbeddedDefaultHasTwoCanBusesALinBusAndOneAdapterOnAllThree) {
  auto c = load_default_config();
  ASSERT_TRUE(c) << c.error().front();
  EXPECT_EQ(c->source, "<embedded default>");
  ASSERT_EQ(c->buses.size(), 3u);
  for (std::size_t i = 0; i < 2; ++i) {
    EXPECT_EQ(c->buses[i].kind, BusKind::can);
    EXPECT_EQ(c->buses[i].bitrate, 500000u);
  }
  EXPECT_EQ(c->buses[2].name, "lin0");
  EXPECT_EQ(c->buses[2].kind, BusKind::lin);
  EXPECT_EQ(c->buses[2].bitrate, 19200u);
  ASSERT_EQ(c->devices.size(), 1u);
  EXPECT_EQ(c->devices[0].model, DeviceModel::ixxat_usb_to_can);
  EXPECT_EQ(c->devices[0].controllers, (std::vector<std::string>{"can0", "can1"}));
  EXPECT_EQ(c->devices[0].lin, (std::vector<std::string>{"lin0"}));
  EXPECT_EQ(c->simulation.time.mode, TimeMode::realtime);
}

TEST(Config, TheShippedDefaultFileIsTheEmbeddedOne) {
  auto file = load_config_file(CANEMU_SOURCE_DIR "/config/default.toml");
  ASSERT_TRUE(file) << file.error().front();
  EXPECT_EQ(summary(*file).substr(summary(*file).find('\n')),
            summary(*load_default_config()).substr(summary(*load_default_config()).find('\n')));
}

TEST(Config, ReadsEveryKey) {
  auto c = parse_config(R"(
[simulation]
time = "scaled:2.5"
seed = 42
batch_us = 40
batch_max_us = 2000
spin_us = 10
cpu_latency_us = 0
[security]
allowed_users = ["alice"]
allowed_groups = ["canemu"]
[[bus]]
name = "fd0"
kind = "can-fd"
bitrate = 1000000
sample_point = 0.8
data_bitrate = 5000000
[[bus]]
name = "lin0"
kind = "lin"
[[device]]
name = "fd-adapter"
model = "ixxat-usb-to-can-fd"
controllers = ["fd0"]
)",
                        "t.toml");
  ASSERT_TRUE(c) << c.error().front();
  EXPECT_EQ(c->simulation.time.mode, TimeMode::scaled);
  EXPECT_DOUBLE_EQ(c->simulation.time.scale, 2.5);
  EXPECT_EQ(c->simulation.seed, 42u);
  EXPECT_EQ(c->simulation.batch_us, 40u);
  EXPECT_EQ(c->simulation.batch_max_us, 2000u);
  EXPECT_EQ(c->simulation.spin_us, 10u);
  EXPECT_EQ(c->simulation.cpu_latency_us, std::optional<uint32_t>(0));
  EXPECT_EQ(c->security.allowed_users, (std::vector<std::string>{"alice"}));
  EXPECT_EQ(c->security.allowed_groups, (std::vector<std::string>{"canemu"}));
  EXPECT_EQ(c->buses[0].kind, BusKind::can_fd);
  EXPECT_EQ(c->buses[0].sample_point, 800u);
  EXPECT_EQ(c->buses[0].data_bitrate, 5000000u);
  EXPECT_EQ(c->buses[1].bitrate, 19200u);  // LIN default
  EXPECT_EQ(c->devices[0].model, DeviceModel::ixxat_usb_to_can_fd);
}

// The socket's mode in octal, its group; errors say the mode in octal.
TEST(Config, SecurityDefaultsAndTheSocketsModeAndGroup) {
  auto plain = parse_config("[[bus]]\nname = \"b\"\n", "t.toml");
  ASSERT_TRUE(plain);
  EXPECT_EQ(plain->security.allowed_groups, (std::vector<std::string>{"canemu"}));
  EXPECT_EQ(plain->security.socket_mode, 0660u);
  EXPECT_EQ(plain->security.socket_group, "canemu");
  auto set = parse_config("[security]\nsocket_mode = 0o600\nsocket_group = \"\"\n", "t.toml");
  ASSERT_TRUE(set);
  EXPECT_EQ(set->security.socket_mode, 0600u);
  EXPECT_EQ(set->security.socket_group, "");
  EXPECT_EQ(config_errors("[security]\nsocket_mode = 0o1777\n"),
            (std::vector<std::string>{
                "t.toml:2:15: security.socket_mode: 0o1777 is outside 0o000..0o777"}));
  EXPECT_EQ(config_errors("[security]\nsocket_mode = \"660\"\n"),
            (std::vector<std::string>{
                "t.toml:2:15: security.socket_mode: must be an integer (octal, such as 0o660)"}));
}

TEST(Config, QuotasPerUser) {
  auto plain = parse_config("[[bus]]\nname = \"b\"\n", "t.toml");
  ASSERT_TRUE(plain);
  EXPECT_EQ(plain->security.max_clients_per_user, 32u);
  EXPECT_EQ(plain->security.ring_mib_per_user, 64u);
  auto set =
      parse_config("[security]\nmax_clients_per_user = 4\nring_mib_per_user = 8\n", "t.toml");
  ASSERT_TRUE(set);
  EXPECT_EQ(set->security.max_clients_per_user, 4u);
  EXPECT_EQ(set->security.ring_mib_per_user, 8u);
  const auto errors =
      config_errors("[security]\nmax_clients_per_user = 0\nring_mib_per_user = 257\n");
  ASSERT_EQ(errors.size(), 2u);
  EXPECT_NE(errors[0].find("t.toml:2:24: security.max_clients_per_user"), std::string::npos)
      << errors[0];
  EXPECT_NE(errors[1].find("t.toml:3:21: security.ring_mib_per_user"), std::string::npos)
      << errors[1];
}

TEST(Config, LowSpeedTransceiversOnSlowClassicBusesOnly) {
  auto cfg = parse_config(
      "[[bus]]\nname = \"body\"\nbitrate = 125000\ntransceiver = \"low-speed\"\n", "t.toml");
  ASSERT_TRUE(cfg);
  EXPECT_TRUE(cfg->buses.at(0).low_speed);
  EXPECT_EQ(config_errors("[[bus]]\nname = \"b\"\nbitrate = 250000\ntransceiver = \"low-speed\"\n"),
            (std::vector<std::string>{"t.toml:4:15: bus[0].transceiver: a low-speed bus runs at up "
                                      "to 125000 bit/s, not 250000"}));
  EXPECT_EQ(config_errors("[[bus]]\nname = \"b\"\nkind = \"can-fd\"\nbitrate = 125000\n"
                          "transceiver = \"low-speed\"\n"),
            (std::vector<std::string>{"t.toml:5:15: bus[0].transceiver: low-speed (ISO 11898-3) "
                                      "transceivers are for classic CAN buses (kind = \"can\")"}));
  EXPECT_EQ(config_errors("[[bus]]\nname = \"b\"\ntransceiver = \"slow\"\n"),
            (std::vector<std::string>{"t.toml:3:15: bus[0].transceiver: \"slow\" is not a "
                                      "transceiver (high-speed, low-speed)"}));
}

TEST(Config, UnknownKeysAreErrorsWithFileLineColumnAndKey) {
  const auto e = config_errors("[[bus]]\nname = \"can0\"\nspeed = 5\n");
  ASSERT_EQ(e.size(), 1u);
  EXPECT_EQ(e[0],
            "t.toml:3:1: bus[0].speed: unknown key (known here: name, kind, bitrate, "
            "sample_point, data_bitrate, transceiver, owner)");
  const auto top = config_errors("[buses]\n");
  ASSERT_EQ(top.size(), 1u);
  EXPECT_NE(top[0].find("t.toml:1:2: buses: unknown key"), std::string::npos) << top[0];
}

TEST(Config, TheBatchWindowDefaultsTo50UsWideningTo1000UsAndIsBounded) {
  auto c = parse_config("[simulation]\n", "t.toml");
  ASSERT_TRUE(c) << c.error().front();
  EXPECT_EQ(c->simulation.batch_us, 50u);
  EXPECT_EQ(c->simulation.batch_max_us, 1000u);
  const auto e = config_errors("[simulation]\nbatch_max_us = 100001\n");
  ASSERT_EQ(e.size(), 1u);
  EXPECT_EQ(e[0], "t.toml:2:16: simulation.batch_max_us: 100001 is outside 0..100000");
}

TEST(Config, NoCpuLatencyRequestUnlessOneIsConfiguredWithinItsBounds) {
  auto c = parse_config("[simulation]\n", "t.toml");
  ASSERT_TRUE(c) << c.error().front();
  EXPECT_FALSE(c->simulation.cpu_latency_us);
  const auto e = config_errors("[simulation]\ncpu_latency_us = -1\n");
  ASSERT_EQ(e.size(), 1u);
  EXPECT_EQ(e[0], "t.toml:2:18: simulation.cpu_latency_us: -1 is outside 0..100000");
}

TEST(Config, CollectsEveryErrorAtOnce) {
  const auto e = config_errors(R"([simulation]
time = "fast"
[[bus]]
name = "can0"
bitrate = 2000000
[[bus]]
name = "can0"
kind = "flexray"
[[device]]
name = "x"
model = "ixxat-usb-to-can"
controllers = ["can9"]
)");
  ASSERT_EQ(e.size(), 5u);
  EXPECT_EQ(e[0],
            "t.toml:2:8: simulation.time: \"fast\" is not a time mode (realtime, stepped, "
            "scaled:F)");
  EXPECT_EQ(e[1], "t.toml:5:11: bus[0].bitrate: 2000000 is outside 5000..1000000");
  EXPECT_EQ(e[2], "t.toml:7:8: bus[1].name: a bus named \"can0\" exists already");
  EXPECT_EQ(e[3], "t.toml:8:8: bus[1].kind: \"flexray\" is not a bus kind (can, can-fd, lin)");
  EXPECT_EQ(e[4], "t.toml:12:15: device[0].controllers: no bus is named \"can9\"");
}

TEST(Config, TakesAThousandTwentyFourBusesAndTwoHundredFiftySixControllersAndNoMore) {
  auto most = parse_config(testing::many_buses_config(1024, 256), "t.toml");
  ASSERT_TRUE(most) << most.error().front();
  EXPECT_EQ(most->buses.size(), 1024u);
  EXPECT_EQ(most->buses.back().name, "bus1023");
  EXPECT_EQ(most->devices.size(), 64u);
  EXPECT_EQ(most->devices[63].controllers.back(), "bus255");
  const auto buses = config_errors(testing::many_buses_config(1025, 4));
  ASSERT_EQ(buses.size(), 1u);
  EXPECT_EQ(buses[0], "t.toml:1:1: bus: 1025 buses; at most 1024");
  const auto controllers = config_errors(testing::many_buses_config(64, 257));
  ASSERT_EQ(controllers.size(), 1u);
  EXPECT_EQ(controllers[0], "t.toml:1:1: device: 257 controllers in all; at most 256");
}

TEST(Config, RejectsControllersOnLinBusesAndDataRatesOnClassicBuses) {
  const auto e = config_errors(R"([[bus]]
name = "lin0"
kind = "lin"
[[bus]]
name = "can0"
data_bitrate = 2000000
[[device]]
name = "a"
model = "ixxat-usb-to-can"
controllers = ["lin0"]
)");
  ASSERT_EQ(e.size(), 2u);
  EXPECT_NE(e[0].find("bus[1].data_bitrate: only a can-fd bus has a data bit rate"),
            std::string::npos);
  EXPECT_NE(e[1].find("\"lin0\" is a LIN bus"), std::string::npos);
}

TEST(Config, RejectsBadNamesMissingKeysAndWrongTypes) {
  const auto e = config_errors(R"([[bus]]
name = "CAN 0"
bitrate = "fast"
[[device]]
model = "ixxat-usb-to-can"
)");
  ASSERT_EQ(e.size(), 4u);
  EXPECT_NE(e[0].find("bus[0].name: must be 1 to 28 characters"), std::string::npos);
  EXPECT_NE(e[1].find("bus[0].bitrate: must be an integer"), std::string::npos);
  EXPECT_NE(e[2].find("device[0].name: missing"), std::string::npos);
  EXPECT_NE(e[3].find("device[0].controllers: missing"), std::string::npos);
}

TEST(Config, DistributedKeysTheirDefaultsAndTheSameHostLink) {
  auto c = parse_config("[distributed]\nname = \"rig-a\"\n", "t.toml");
  ASSERT_TRUE(c) << c.error().front();
  EXPECT_TRUE(c->distributed.enabled);
  EXPECT_EQ(c->distributed.name, "rig-a");
  EXPECT_EQ(c->distributed.heartbeat_ms, 200u);
  EXPECT_EQ(c->distributed.timeout_ms, 2000u);
  EXPECT_TRUE(c->distributed.local_link);  // daemons on one host take their link by default
  auto off = parse_config("[distributed]\nname = \"rig-a\"\nlocal_link = false\n", "t.toml");
  ASSERT_TRUE(off) << off.error().front();
  EXPECT_FALSE(off->distributed.local_link);
  const auto e = config_errors("[distributed]\nname = \"rig-a\"\nlocal_link = \"yes\"\n");
  ASSERT_EQ(e.size(), 1u);
  EXPECT_NE(e[0].find("distributed.local_link: must be true or false"), std::string::npos) << e[0];
}

TEST(Config, SyntaxErrorsNameTheirPlace) {
  const auto e = config_errors("[[bus]\n");
  ASSERT_EQ(e.size(), 1u);
  EXPECT_EQ(e[0].rfind("t.toml:1:", 0), 0u) << e[0];
  EXPECT_NE(e[0].find("syntax"), std::string::npos);
}

TEST(Config, MissingFileIsAClearError) {
  auto c = load_config_file("/nonexistent/canemu.toml");
  ASSERT_FALSE(c);
  EXPECT_EQ(c.error().front(),
            "/nonexistent/canemu.toml: cannot be read (No such file or directory)");
}

// Files a person names are read whole but bounded: a device without end, a directory or a
// huge file is an error that says so, never a process that reads until memory runs out.
TEST(Config, AFileWithoutEndADirectoryAndAHugeFileAreClearErrors) {
  auto zero = load_config_file("/dev/zero");
  ASSERT_FALSE(zero);
  EXPECT_EQ(zero.error().front(),
            "/dev/zero: larger than 1 MiB, the most canemu reads from such a file");
  testing::TempDir dir;
  auto folder = load_config_file(dir.path.string());
  ASSERT_FALSE(folder);
  EXPECT_EQ(folder.error().front(), dir.path.string() + ": is a directory, not a file");
  const std::string huge = (dir.path / "huge.toml").string();
  {
    std::ofstream f(huge);
    f << std::string(kMaxConfigFileBytes, '#') << "\n";
  }
  auto big = load_config_file(huge);
  ASSERT_FALSE(big);
  EXPECT_EQ(big.error().front(),
            huge + ": larger than 1 MiB, the most canemu reads from such a file");
  auto scenario = load_scenario_file("/dev/zero");
  ASSERT_FALSE(scenario);
  EXPECT_NE(scenario.error().front().find("/dev/zero: larger than 1 MiB"), std::string::npos);
}

// [security] lists are looked up at every reload in the event loop: they are short.
TEST(Config, SecurityListsAreBounded) {
  std::string users;
  for (std::size_t i = 0; i <= kMaxSecurityNames; ++i) {
    users += fmt::format("{}\"user{}\"", i == 0 ? "" : ", ", i);
  }
  const auto e = config_errors("[security]\nallowed_users = [" + users + "]\n");
  ASSERT_EQ(e.size(), 1u);
  EXPECT_EQ(e[0], fmt::format("t.toml:2:17: security.allowed_users: {} entries; at most {} (give "
                              "more users a group and list the group)",
                              kMaxSecurityNames + 1, kMaxSecurityNames));
  users.resize(users.rfind(','));  // exactly the most allowed
  EXPECT_TRUE(parse_config("[security]\nallowed_users = [" + users + "]\n", "t.toml"));
}

TEST(TimeSetting, ParsesTheThreeModes) {
  EXPECT_EQ(parse_time_setting("realtime")->mode, TimeMode::realtime);
  EXPECT_EQ(parse_time_setting("stepped")->mode, TimeMode::stepped);
  auto s = parse_time_setting("scaled:0.5");
  ASSERT_TRUE(s);
  EXPECT_EQ(s->mode, TimeMode::scaled);
  EXPECT_DOUBLE_EQ(s->scale, 0.5);
  EXPECT_EQ(to_string(*s), "scaled:0.5");
  EXPECT_FALSE(parse_time_setting("scaled:0"));
  EXPECT_FALSE(parse_time_setting("scaled:abc"));
  EXPECT_FALSE(parse_time_setting("scaled:"));
  EXPECT_FALSE(parse_time_setting("Realtime"));
}

}  // namespace
}  // namespace canemu::daemon
