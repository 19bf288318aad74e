// canemu dump's bus arguments in candump's syntax and its filters as the kernel applies them
// (can-utils' candump help text and its examples, linux/can.h, af_can.c, raw.c).
#include "dump_filter.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <ctime>

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
  EXPECT_TRUE(b.matches(kSff123));
  EXPECT_TRUE(b.matches(kSff123Remote));
  EXPECT_TRUE(b.matches(kEff123));
  EXPECT_FALSE(b.matches(frame(0x124)));
  EXPECT_TRUE(b.matches(frame(0x7123 | sc::kEffFlag)));  // only the low 11 bits are asked
  // "candump vcan2,123:C00007FF (matches CAN ID 123 - only SFF and non-RTR frames)"
  const BusFilter sff = parse("can0,123:C00007FF");
  EXPECT_TRUE(sff.matches(kSff123));
  EXPECT_FALSE(sff.matches(kSff123Remote));
  EXPECT_FALSE(sff.matches(kEff123));
  // A mask with CAN_EFF_FLAG and an 11-bit identifier: 11-bit frames only, whatever the mask
  // says about bits 11..28 (the kernel cuts it to SFF | EFF | RTR).
  const BusFilter sff_only = parse("can0,123:9FFFFFFF");
  EXPECT_TRUE(sff_only.matches(kSff123));
  EXPECT_FALSE(sff_only.matches(kEff123));
  EXPECT_FALSE(sff_only.matches(frame(0x7123 | sc::kEffFlag)));
}

TEST(CliDumpFilter, AnIdentifierOfEightDigitsIsExtended) {
  // "candump vcan2,12345678:DFFFFFFF (match only for extended CAN ID 12345678)"
  const BusFilter b = parse("can0,12345678:DFFFFFFF");
  EXPECT_TRUE(b.matches(frame(0x12345678 | sc::kEffFlag)));
  EXPECT_FALSE(b.matches(frame(0x12345678 | sc::kEffFlag | sc::kRtrFlag)));
  EXPECT_FALSE(b.matches(frame(0x12345679 | sc::kEffFlag)));
  // The width decides, not the value: 00000123 asks for the extended 123, 123 for the 11-bit.
  const BusFilter eff = parse("can0,00000123:800007FF");
  EXPECT_TRUE(eff.matches(kEff123));
  EXPECT_FALSE(eff.matches(kSff123));
  const BusFilter sff = parse("can0,123:800007FF");
  EXPECT_TRUE(sff.matches(kSff123));
  EXPECT_FALSE(sff.matches(kEff123));
}

TEST(CliDumpFilter, InverseFiltersAndSeveralFilters) {
  const BusFilter inv = parse("can0,400~7F0");
  EXPECT_TRUE(inv.matches(kSff123));
  EXPECT_FALSE(inv.matches(frame(0x405)));
  // "0~0" matches no frame at all (candump -l any,0~0,#FFFFFFFF logs error frames only).
  const BusFilter none = parse("any,0~0,#FFFFFFFF");
  EXPECT_FALSE(none.matches(kSff123));
  EXPECT_FALSE(none.matches(kEff123));
  EXPECT_TRUE(none.matches(kBusError));
  // Several filters: any of them.
  const BusFilter two = parse("can0,123:7FF,400:700");
  EXPECT_TRUE(two.matches(kSff123));
  EXPECT_TRUE(two.matches(frame(0x4AB)));
  EXPECT_FALSE(two.matches(frame(0x124)));
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
  EXPECT_TRUE(any_of.matches(frame(0x150)));
  EXPECT_TRUE(all_of.matches(frame(0x150)));
  EXPECT_TRUE(any_of.matches(frame(0x1FF)));
  EXPECT_FALSE(all_of.matches(frame(0x1FF)));
  EXPECT_TRUE(any_of.matches(frame(0x250)));
  EXPECT_FALSE(all_of.matches(frame(0x250)));
}

TEST(CliDumpFilter, ErrorFramesComeByTheirClassesOnly) {
  // A bus alone takes every frame and every error frame (canemu dump's default).
  const BusFilter alone = parse("can0");
  EXPECT_EQ(alone.bus, "can0");
  EXPECT_FALSE(alone.filtered);
  EXPECT_EQ(alone.error_mask, kErrMask);
  for (const sc::Frame& f : {kSff123, kSff123Remote, kEff123, kBusError, kBusOff}) {
    EXPECT_TRUE(alone.matches(f)) << std::hex << f.can_id;
  }
  EXPECT_EQ(alone.describe(), "");
  EXPECT_EQ(parse("any").bus, "any");
  // A filter list without #mask takes no error frames, as candump's socket does.
  const BusFilter plain = parse("can0,123:7FF");
  EXPECT_EQ(plain.error_mask, 0u);
  EXPECT_FALSE(plain.matches(kBusError));
  EXPECT_FALSE(plain.matches(kBusOff));
  // #40: bus-off only; data frames are not touched by it (no frame filter: all of them).
  const BusFilter busoff = parse("can0,#40");
  EXPECT_EQ(busoff.error_mask, sc::kErrBusOff);
  EXPECT_TRUE(busoff.matches(kBusOff));
  EXPECT_FALSE(busoff.matches(kBusError));
  EXPECT_TRUE(busoff.matches(kSff123));
  EXPECT_TRUE(busoff.matches(kEff123));
  // Error frames are never matched against the frame filters, joined or not.
  const BusFilter joined = parse("can0,123:7FF,124:7FF,j,#FFFFFFFF");
  EXPECT_EQ(joined.error_mask, kErrMask);
  EXPECT_TRUE(joined.matches(kBusError));
  EXPECT_FALSE(joined.matches(kSff123));
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
