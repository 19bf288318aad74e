// The logging facade: sd-daemon priority prefixes, the program name, the simulated time where a
// line carries one, the level filter and the capture tests use.
#include "canemu/daemon/base/log.hpp"

#include <gtest/gtest.h>

namespace canemu::daemon {
namespace {

TEST(Log, EachLevelHasItsSdDaemonPriorityPrefix) {
  EXPECT_EQ(log::prefix(log::Level::error), "<3>");
  EXPECT_EQ(log::prefix(log::Level::warning), "<4>");
  EXPECT_EQ(log::prefix(log::Level::notice), "<5>");
  EXPECT_EQ(log::prefix(log::Level::info), "<6>");
  EXPECT_EQ(log::prefix(log::Level::debug), "<7>");
}

TEST(Log, ALineIsThePrefixTheProgramNameAndTheFormattedMessage) {
  log::Capture capture;
  log::warning("client {} ({}): a ring was corrupted; disconnecting", 42, "vci_talk");
  log::error("reload: {}", "x.toml:3:1: bus[0].speed: unknown key");
  log::info("listening on {}", "/run/canemu/canemud.sock");
  log::notice("n");
  log::debug("d");
  EXPECT_EQ(
      capture.lines(),
      (std::vector<std::string>{
          "<4>canemud: client 42 (vci_talk): a ring was corrupted; disconnecting",
          "<3>canemud: reload: x.toml:3:1: bus[0].speed: unknown key",
          "<6>canemud: listening on /run/canemu/canemud.sock", "<5>canemud: n", "<7>canemud: d"}));
}

TEST(Log, ALineAtASimulatedInstantCarriesItInSecondsWithNineDecimalsAfterItsTopic) {
  log::Capture capture;
  log::info(log::At{"fault", model::SimTime::from_ns(96'000)}, "scenario \"{}\" cleared", "noisy");
  log::info(log::At{"fault", model::SimTime{}}, "applied");
  // Exact at any time: 10^7 s and one nanosecond (a double would round the last digit).
  log::info(log::At{"fault", model::SimTime::from_ns(10'000'000'000'000'001)}, "late");
  EXPECT_EQ(capture.lines(), (std::vector<std::string>{
                                 "<6>canemud: fault: t=0.000096000 s: scenario \"noisy\" cleared",
                                 "<6>canemud: fault: t=0.000000000 s: applied",
                                 "<6>canemud: fault: t=10000000.000000001 s: late"}));
}

TEST(Log, LinesBelowTheMaximumLevelAreDropped) {
  log::Capture capture;
  log::set_max_level(log::Level::warning);
  log::info("dropped");
  log::notice("dropped");
  log::warning("kept");
  log::error("kept too");
  log::set_max_level(log::Level::debug);
  log::debug("kept again");
  EXPECT_EQ(capture.lines(), (std::vector<std::string>{"<4>canemud: kept", "<3>canemud: kept too",
                                                       "<7>canemud: kept again"}));
}

TEST(Log, FormatLineBuildsTheLineWithoutWritingIt) {
  log::Capture capture;
  EXPECT_EQ(log::format_line(log::Level::info, "x"), "<6>canemud: x");
  EXPECT_TRUE(capture.lines().empty());
}

}  // namespace
}  // namespace canemu::daemon
