// canemu dump's bus arguments in candump's syntax and its filters as the kernel applies them
// (can-utils' candump help text and its examples, linux/can.h, af_can.c, raw.c).
#include "dump_filter.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <ctime>
#include <initializer_list>

namespace canemu::cli {
namespace {

namespace sc = ipc::socketcan;

sc::Frame frame(uint32_t can_id) {
  sc::Frame f;
  f.can_id = can_id;
  return f;
}

BusFilter parse(std::string_view arg) {
  std::string error;
  auto b = parse_bus_filter(arg, error);
  EXPECT_TRUE(b) << arg << ": " << error;
  return b ? *b : BusFilter{};
}

// `b` lets every frame of `pass` through and none of `drop`.
void expect_passes(const BusFilter& b, std::initializer_list<sc::Frame> pass,
                   std::initializer_list<sc::Frame> drop) {
  for (const sc::Frame& f : pass) {
    EXPECT_TRUE(b.matches(f)) << b.describe() << ": " << std::hex << f.can_id;
  }
  for (const sc::Frame& f : drop) {
    EXPECT_FALSE(b.matches(f)) << b.describe() << ": " << std::hex << f.can_id;
  }
}

const sc::Frame kSff123 = frame(0x123);
const sc::Frame kSff123Remote = frame(0x123 | sc::kRtrFlag);
const sc::Frame kEff123 = frame(0x123 | sc::kEffFlag);
const sc::Frame kBusError = frame(sc::kErrFlag | sc::kErrProt | sc::kErrBusError | sc::kErrCnt);
const sc::Frame kBusOff = frame(sc::kErrFlag | sc::kErrBusOff | sc::kErrCnt);

TEST(CliDumpFilter, IdAndMaskMatchAsCandumpSays) {
  // "candump vcan2,123:7FF (matches CAN ID 123 - including EFF and RTR frames)"
  const BusFilter b = parse("can0,123:7FF");
  EXPECT_EQ(b.bus, "can0");
  EXPECT_TRUE(b.filtered);
  // Only the low 11 bits are asked: 7123h extended passes too.
  expect_passes(b, {kSff123, kSff123Remote, kEff123, frame(0x7123 | sc::kEffFlag)}, {frame(0x124)});
  // "candump vcan2,123:C00007FF (matches CAN ID 123 - only SFF and non-RTR frames)"
  expect_passes(parse("can0,123:C00007FF"), {kSff123}, {kSff123Remote, kEff123});
  // A mask with CAN_EFF_FLAG and an 11-bit identifier: 11-bit frames only, whatever the mask
  // says about bits 11..28 (the kernel cuts it to SFF | EFF | RTR).
  expect_passes(parse("can0,123:9FFFFFFF"), {kSff123}, {kEff123, frame(0x7123 | sc::kEffFlag)});
}

TEST(CliDumpFilter, AnIdentifierOfEightDigitsIsExtended) {
  // "candump vcan2,12345678:DFFFFFFF (match only for extended CAN ID 12345678)"
  expect_passes(
      parse("can0,12345678:DFFFFFFF"), {frame(0x12345678 | sc::kEffFlag)},
      {frame(0x12345678 | sc::kEffFlag | sc::kRtrFlag), frame(0x12345679 | sc::kEffFlag)});
  // The width decides, not the value: 00000123 asks for the extended 123, 123 for the 11-bit.
  expect_passes(parse("can0,00000123:800007FF"), {kEff123}, {kSff123});
  expect_passes(parse("can0,123:800007FF"), {kSff123}, {kEff123});
}

TEST(CliDumpFilter, InverseFiltersAndSeveralFilters) {
  expect_passes(parse("can0,400~7F0"), {kSff123}, {frame(0x405)});
  // "0~0" matches no frame at all (candump -l any,0~0,#FFFFFFFF logs error frames only).
  expect_passes(parse("any,0~0,#FFFFFFFF"), {kBusError}, {kSff123, kEff123});
  // Several filters: any of them.
  expect_passes(parse("can0,123:7FF,400:700"), {kSff123, frame(0x4AB)}, {frame(0x124)});
  // A mask's CAN_ERR_FLAG is dropped (candump), so it stays a frame filter.
  EXPECT_TRUE(parse("can0,123:200007FF").matches(kSff123));
}

TEST(CliDumpFilter, JoinAsksForEveryFilter) {
  // 100..1FF and not 1FF.
  const BusFilter any_of = parse("can0,100:700,1FF~7FF");
  const BusFilter all_of = parse("can0,100:700,1FF~7FF,j");
  EXPECT_FALSE(any_of.join);
  EXPECT_TRUE(all_of.join);
  EXPECT_TRUE(parse("can0,J,100:700").join);
  expect_passes(any_of, {frame(0x150), frame(0x1FF), frame(0x250)}, {});
  expect_passes(all_of, {frame(0x150)}, {frame(0x1FF), frame(0x250)});
}

TEST(CliDumpFilter, ErrorFramesComeByTheirClassesOnly) {
  // A bus alone takes every frame and every error frame (canemu dump's default).
  const BusFilter alone = parse("can0");
  EXPECT_EQ(alone.bus, "can0");
  EXPECT_FALSE(alone.filtered);
  EXPECT_EQ(alone.error_mask, kErrMask);
  expect_passes(alone, {kSff123, kSff123Remote, kEff123, kBusError, kBusOff}, {});
  EXPECT_EQ(alone.describe(), "");
  EXPECT_EQ(parse("any").bus, "any");
  // A filter list without #mask takes no error frames, as candump's socket does.
  const BusFilter plain = parse("can0,123:7FF");
  EXPECT_EQ(plain.error_mask, 0u);
  expect_passes(plain, {}, {kBusError, kBusOff});
  // #40: bus-off only; data frames are not touched by it (no frame filter: all of them).
  const BusFilter busoff = parse("can0,#40");
  EXPECT_EQ(busoff.error_mask, sc::kErrBusOff);
  expect_passes(busoff, {kBusOff, kSff123, kEff123}, {kBusError});
  // Error frames are never matched against the frame filters, joined or not.
  const BusFilter joined = parse("can0,123:7FF,124:7FF,j,#FFFFFFFF");
  EXPECT_EQ(joined.error_mask, kErrMask);
  expect_passes(joined, {kBusError}, {kSff123});
  // The last #mask counts, as in candump.
  EXPECT_EQ(parse("can0,#8,#80").error_mask, 0x80u);
}

TEST(CliDumpFilter, WhatIsNoFilterIsRefusedSayingWhy) {
  for (const char* bad :
       {"can0,", "can0,,123:7FF", "can0,xyz", "can0,123:", "can0,:7FF", "can0,123456789:7FF",
        "can0,123:7FFG", "can0,#", "can0,#xyz", "can0,123:123456789", "can0,jj"}) {
    std::string error;
    EXPECT_FALSE(parse_bus_filter(bad, error)) << bad;
    EXPECT_NE(error.find("is not <id>:<mask>, <id>~<mask>, #<error mask> or j"), std::string::npos)
        << bad << ": " << error;
  }
  std::string error;
  EXPECT_FALSE(parse_bus_filter(",123:7FF", error));
  EXPECT_NE(error.find("no bus name"), std::string::npos) << error;
}

TEST(CliDumpFilter, DescribesWhatGetsThrough) {
  EXPECT_EQ(parse("can0,123:7FF,400~7F0").describe(),
            "frames that match 123:7FF or 400~7F0; no error frames (#<mask> selects them)");
  EXPECT_EQ(parse("can0,100:700,1FF~7FF,J,#FFFFFFFF").describe(),
            "frames that match 100:700 and 1FF~7FF; error frames of classes 1FFFFFFF");
  EXPECT_EQ(parse("can1,#40").describe(), "every frame; error frames of classes 00000040");
}

TEST(CliDumpFilter, TheLogFileIsNamedAsCandumpNamesIt) {
  ::setenv("TZ", "UTC", 1);
  ::tzset();
  EXPECT_EQ(candump_log_name(1'700'000'000), "candump-2023-11-14_221320.log");
  EXPECT_EQ(candump_log_name(0), "candump-1970-01-01_000000.log");
}

}  // namespace
}  // namespace canemu::cli
