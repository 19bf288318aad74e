// canemu's VCI extension calls for simulated CAN nodes (canemu_vci.h, docs/restbus.md) through
// libvcinpl, in stepped time: canemuLoadCanNodes starts [[can_node]] tables whose frames reach
// the program's channel with their exact bytes and time stamps (ticks of 1 us from canemud's
// start), canemuEnumCanNodes lists the nodes, canemuSetSignal changes the next frame and
// canemuGetSignal reads it back, canemuPowerCanNode and canemuRemoveCanNode switch and take off
// a node; each refusal is VCI_E_INVALIDARG with canemud's reason as vciFormatError's detail, and
// changes nothing.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "canemu/ipc/can_node_messages.hpp"
#include "vci_c_test_support.hpp"

namespace canemu::testing {
namespace {

using Texts = std::vector<std::string>;

// ENGINE sends ENGINE_DATA (0x120, 4 bytes) every 10 ms from 2 ms: a 4-bit alive counter, a
// scaled and offset signed temperature with a range, and a CRC-8 SAE J1850 with a data ID.
// BRAKE sends BRAKE_STATUS (0x200, 1 byte) every 20 ms from 5 ms: one 8-bit signal without a
// range. Their instants never meet, so no frame waits for another.
const char* const kTables = R"([[can_node]]
name = "ENGINE"
bus = "can0"

[[can_node.message]]
name = "ENGINE_DATA"
id = 0x120
length = 4
cycle = "10ms"
delay = "2ms"

[[can_node.message.signal]]
name = "ENGINE_ALIVE"
start = 0
length = 4
counter = true

[[can_node.message.signal]]
name = "ENGINE_TEMP"
start = 8
length = 16
signed = true
scale = 0.5
offset = -10.0
minimum = -40.0
maximum = 200.0
initial = 85.5
unit = "degC"

[[can_node.message.signal]]
name = "ENGINE_CRC"
start = 24
length = 8
checksum = "crc8_sae_j1850"
data_id = 0x1234

[[can_node]]
name = "BRAKE"
bus = "can0"

[[can_node.message]]
name = "BRAKE_STATUS"
id = 0x200
length = 1
cycle = "20ms"
delay = "5ms"

[[can_node.message.signal]]
name = "BRAKE_PRESSURE"
start = 0
length = 8
)";

constexpr uint64_t kMs = 1'000'000;
constexpr int kTemp = 191;  // ENGINE_TEMP's raw start value: (85.5 + 10) / 0.5

// CRC-8 SAE J1850 (polynomial 0x1D, start 0xFF, final XOR 0xFF), written here on its own.
uint8_t crc8_sae_j1850(const std::vector<uint8_t>& bytes) {
  uint8_t crc = 0xFF;
  for (uint8_t b : bytes) {
    crc ^= b;
    for (int i = 0; i < 8; ++i) {
      crc = static_cast<uint8_t>((crc & 0x80) != 0 ? (crc << 1) ^ 0x1D : crc << 1);
    }
  }
  return static_cast<uint8_t>(crc ^ 0xFF);
}

// ENGINE_DATA's bytes for the counter `alive` and the raw temperature `temp`: the CRC covers the
// data ID (low byte first) and the other three bytes.
std::vector<uint8_t> engine_data(unsigned alive, int temp) {
  std::vector<uint8_t> b{static_cast<uint8_t>(alive & 0x0F), static_cast<uint8_t>(temp & 0xFF),
                         static_cast<uint8_t>((temp >> 8) & 0xFF)};
  b.push_back(crc8_sae_j1850({0x34, 0x12, b[0], b[1], b[2]}));
  return b;
}

// A received frame as text: "TIME ID#BYTES" (time in ticks of 1 us, id and bytes in hex).
std::string text(UINT32 time, UINT32 id, const UINT8* bytes, unsigned dlc) {
  char line[64];
  int n = std::snprintf(line, sizeof line, "%u %03X#", time, id);
  for (unsigned i = 0; i < dlc; ++i) {
    n += std::snprintf(line + n, sizeof line - n, "%02X", bytes[i]);
  }
  return line;
}

std::vector<std::string> texts(const std::vector<CANMSG>& msgs) {
  Texts got;
  for (const CANMSG& m : msgs) {
    got.push_back(text(m.dwTime, m.dwMsgId, m.abData, m.uMsgInfo.Bits.dlc));
  }
  return got;
}

// A frame queued at `start_ms` on an idle bus: received at its end (500 kbit/s).
std::string sent(uint32_t start_ms, UINT32 id, const std::vector<uint8_t>& bytes) {
  const auto end = static_cast<UINT32>(start_ms * 1000 + bits_of(id, bytes) * kBitUs2);
  return text(end, id, bytes.data(), static_cast<unsigned>(bytes.size()));
}

// The nodes canemuEnumCanNodes lists, "NAME BUS on|off MESSAGES FRAMES", until it says
// VCI_E_NO_MORE_ITEMS.
Texts nodes() {
  Texts got;
  CANEMU_CANNODEINFO info{};
  UINT32 i = 0;
  HRESULT hr = VCI_OK;
  while ((hr = canemuEnumCanNodes(i++, &info)) == VCI_OK) {
    got.push_back(std::string(info.szName) + " " + info.szBus + (info.bPowered ? " on " : " off ") +
                  std::to_string(info.dwMessages) + " " + std::to_string(info.qwFrames));
  }
  EXPECT_EQ(hr, VCI_E_NO_MORE_ITEMS);
  return got;
}

// What vciFormatError says of a call's result (a text bigger than VCI_MAX_ERRSTRLEN fits).
std::string said(HRESULT hr) {
  char text[4096];
  vciFormatError(hr, text, sizeof text);
  return hr == VCI_E_INVALIDARG ? text : "not VCI_E_INVALIDARG: " + std::string(text);
}

double get(const char* bus, const char* signal) {
  double value = -12345;
  EXPECT_EQ(canemuGetSignal(bus, signal, &value), VCI_OK) << said(VCI_E_INVALIDARG);
  return value;
}

// canemud in stepped time with the adapter alpha on can0, kTables loaded at 0 and alpha's
// channel started at 0.
class VciRestbus : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_EQ(canemuLoadCanNodes(kTables, "restbus.toml"), VCI_OK) << said(VCI_E_INVALIDARG);
  }
  VciDaemon daemon_;
  Adapter alpha_{"alpha"};
  SimClock clock_;
};

TEST_F(VciRestbus, LoadedNodesSendTheirFramesAtTheirInstantsAndAreListed) {
  EXPECT_EQ(nodes(), (Texts{"ENGINE can0 on 1 0", "BRAKE can0 on 1 0"}));
  clock_.to(30 * kMs);
  // The counter goes up per frame; the CRC follows it.
  EXPECT_EQ(texts(alpha_.frames()),
            (Texts{sent(2, 0x120, engine_data(0, kTemp)), sent(5, 0x200, {0x00}),
                   sent(12, 0x120, engine_data(1, kTemp)), sent(22, 0x120, engine_data(2, kTemp)),
                   sent(25, 0x200, {0x00})}));
  EXPECT_EQ(nodes(), (Texts{"ENGINE can0 on 1 3", "BRAKE can0 on 1 2"}));
  // Past the end as canemuEnumBuses; no place for the entry.
  CANEMU_BUSINFO bus{};
  EXPECT_EQ(canemuEnumBuses(1, &bus), VCI_E_NO_MORE_ITEMS);
  CANEMU_CANNODEINFO info{};
  EXPECT_EQ(canemuEnumCanNodes(2, &info), VCI_E_NO_MORE_ITEMS);
  EXPECT_EQ(canemuEnumCanNodes(0, nullptr), VCI_E_INVALIDARG);
  EXPECT_EQ(get("can0", "ENGINE_DATA.ENGINE_TEMP"), 85.5);
  EXPECT_EQ(get("can0", "ENGINE_DATA.ENGINE_ALIVE"), 3);  // the next frame's
}

TEST_F(VciRestbus, ASetSignalGoesInTheNextFrameAndGetSignalReadsIt) {
  clock_.to(3 * kMs);
  ASSERT_EQ(canemuSetSignal("can0", "ENGINE_DATA.ENGINE_TEMP", -30), VCI_OK);
  EXPECT_EQ(get("can0", "ENGINE_DATA.ENGINE_TEMP"), -30);
  ASSERT_EQ(canemuSetSignal("can0", "BRAKE_STATUS.BRAKE_PRESSURE", 255), VCI_OK);
  clock_.to(13 * kMs);
  EXPECT_EQ(texts(alpha_.frames()),
            (Texts{sent(2, 0x120, engine_data(0, kTemp)), sent(5, 0x200, {0xFF}),
                   sent(12, 0x120, engine_data(1, -40))}));  // raw -40: D8 FF
  // 20.25 is raw 60.5: rounded half to even, 60, which reads back as 20.
  ASSERT_EQ(canemuSetSignal("can0", "ENGINE_DATA.ENGINE_TEMP", 20.25), VCI_OK);
  EXPECT_EQ(get("can0", "ENGINE_DATA.ENGINE_TEMP"), 20.0);
  // A counter set is the next frame's value; a checksum reads as the next frame's.
  ASSERT_EQ(canemuSetSignal("can0", "ENGINE_DATA.ENGINE_ALIVE", 9), VCI_OK);
  EXPECT_EQ(get("can0", "ENGINE_DATA.ENGINE_ALIVE"), 9);
  EXPECT_EQ(get("can0", "ENGINE_DATA.ENGINE_CRC"), engine_data(9, 60)[3]);
  clock_.to(23 * kMs);
  EXPECT_EQ(texts(alpha_.frames()), (Texts{sent(22, 0x120, engine_data(9, 60))}));
  EXPECT_EQ(get("can0", "ENGINE_DATA.ENGINE_ALIVE"), 10);
}

TEST_F(VciRestbus, EachRefusalSaysCanemudsReasonAndChangesNothing) {
  clock_.to(3 * kMs);
  const Texts before = nodes();
  double value = 0;
  const char* temp = "ENGINE_DATA.ENGINE_TEMP";
  const char* pressure = "BRAKE_STATUS.BRAKE_PRESSURE";
  const std::string no_engine = "invalid argument (no simulated CAN node named \"NOPE\")";
  EXPECT_EQ(said(canemuSetSignal(nullptr, temp, 1)),
            "invalid argument (the bus and MESSAGE.SIGNAL are needed)");
  EXPECT_EQ(said(canemuSetSignal("can0", nullptr, 1)),
            "invalid argument (the bus and MESSAGE.SIGNAL are needed)");
  EXPECT_EQ(said(canemuGetSignal(nullptr, temp, &value)),
            "invalid argument (the bus and MESSAGE.SIGNAL are needed)");
  EXPECT_EQ(said(canemuGetSignal("can0", temp, nullptr)),
            "invalid argument (a place for the value is needed)");
  for (const char* bad : {"ENGINE_DATA", "ENGINE_DATA.", ".ENGINE_TEMP", ""}) {
    EXPECT_EQ(said(canemuSetSignal("can0", bad, 1)),
              "invalid argument (\"" + std::string(bad) + "\" is not MESSAGE.SIGNAL)");
  }
  EXPECT_EQ(said(canemuSetSignal("can9", temp, 1)), "invalid argument (no bus is named \"can9\")");
  EXPECT_EQ(said(canemuSetSignal("can0", "NO_MSG.ENGINE_TEMP", 1)),
            "invalid argument (no simulated CAN node sends a message named \"NO_MSG\" on can0)");
  EXPECT_EQ(said(canemuGetSignal("can0", "ENGINE_DATA.NO_SIG", &value)),
            "invalid argument (message ENGINE_DATA has no signal named \"NO_SIG\")");
  EXPECT_EQ(said(canemuSetSignal("can0", "ENGINE_DATA.NO_SIG", 1)),
            "invalid argument (message ENGINE_DATA has no signal named \"NO_SIG\")");
  // Outside the range (the signal has one), outside the bits (it has none), not a number.
  EXPECT_EQ(said(canemuSetSignal("can0", temp, 200.5)),
            "invalid argument (200.5 is outside the range of ENGINE_DATA.ENGINE_TEMP: -40..200 "
            "degC)");
  EXPECT_EQ(said(canemuSetSignal("can0", temp, -40.5)),
            "invalid argument (-40.5 is outside the range of ENGINE_DATA.ENGINE_TEMP: -40..200 "
            "degC)");
  EXPECT_EQ(said(canemuSetSignal("can0", pressure, 256)),
            "invalid argument (256 cannot be the value of BRAKE_STATUS.BRAKE_PRESSURE: 256 is "
            "outside what 8 unsigned bits hold (0 .. 255))");
  EXPECT_EQ(said(canemuSetSignal("can0", pressure, -1)),
            "invalid argument (-1 cannot be the value of BRAKE_STATUS.BRAKE_PRESSURE: -1 is "
            "outside what 8 unsigned bits hold (0 .. 255))");
  EXPECT_EQ(said(canemuSetSignal("can0", pressure, std::nan(""))),
            "invalid argument (nan cannot be the value of BRAKE_STATUS.BRAKE_PRESSURE: nan is "
            "not a number a signal can carry)");
  EXPECT_EQ(said(canemuSetSignal("can0", "ENGINE_DATA.ENGINE_ALIVE", 16)),
            "invalid argument (16 cannot be the value of ENGINE_DATA.ENGINE_ALIVE: 16 is outside "
            "what 4 unsigned bits hold (0 .. 15))");
  EXPECT_EQ(said(canemuSetSignal("can0", "ENGINE_DATA.ENGINE_CRC", 1)),
            "invalid argument (ENGINE_DATA.ENGINE_CRC is a checksum: it is computed as each "
            "frame goes out)");
  // Nodes.
  EXPECT_EQ(said(canemuPowerCanNode(nullptr, FALSE)), "invalid argument (a node is needed)");
  EXPECT_EQ(said(canemuRemoveCanNode(nullptr)), "invalid argument (a node is needed)");
  EXPECT_EQ(said(canemuPowerCanNode("NOPE", FALSE)), no_engine);
  EXPECT_EQ(said(canemuRemoveCanNode("NOPE")), no_engine);
  EXPECT_EQ(said(canemuPowerCanNode("can9/ENGINE", FALSE)),
            "invalid argument (no simulated CAN node named \"can9/ENGINE\")");
  EXPECT_EQ(said(canemuLoadCanNodes(nullptr, "restbus.toml")),
            "invalid argument (the tables are needed)");
  const std::string too_long(ipc::kMaxCanNodeLoad + 1, '\n');  // 1 MiB, as a configuration file
  EXPECT_EQ(said(canemuLoadCanNodes(too_long.c_str(), nullptr)),
            "invalid argument (the tables are longer than 1048576 bytes)");
  // A later failure without a reason of its own does not carry the last one's.
  EXPECT_EQ(said(canemuEnumCanNodes(0, nullptr)), "invalid argument");
  // Nothing changed: the same nodes, the values as loaded, the next frames as before.
  EXPECT_EQ(nodes(), before);
  EXPECT_EQ(get("can0", temp), 85.5);
  EXPECT_EQ(get("can0", pressure), 0);
  clock_.to(13 * kMs);
  EXPECT_EQ(texts(alpha_.frames()),
            (Texts{sent(2, 0x120, engine_data(0, kTemp)), sent(5, 0x200, {0x00}),
                   sent(12, 0x120, engine_data(1, kTemp))}));
}

TEST_F(VciRestbus, RefusedTablesSayEveryMistakeAndNoneOfThemStarts) {
  clock_.to(3 * kMs);
  // BRAKE again (it would replace the running one) and a node with two mistakes.
  const std::string bad = R"([[can_node]]
name = "BRAKE"
bus = "can0"

[[can_node.message]]
name = "BRAKE_STATUS2"
id = 0x201
length = 1
cycle = "20ms"

[[can_node]]
name = "GEARBOX"
bus = "can9"

[[can_node.message]]
name = "GEAR"
id = 0x300
length = 9
cycle = "20ms"
)";
  EXPECT_EQ(said(canemuLoadCanNodes(bad.c_str(), "bad.toml")),
            "invalid argument (bad.toml:13:7: can_node[1].bus: no bus is named \"can9\"\n"
            "bad.toml:18:10: can_node[1].message[0].length: 9 bytes: a classic frame has 0 to 8 "
            "(fd = true for more))");
  // Without a source canemud names the text "can nodes". A message name and an identifier
  // that other nodes send on can0 already.
  const char* const taken =
      "[[can_node]]\nname = \"OTHER\"\nbus = \"can0\"\n\n"
      "[[can_node.message]]\nname = \"ENGINE_DATA\"\nid = 0x121\nlength = 1\ncycle = \"20ms\"\n\n"
      "[[can_node.message]]\nname = \"OTHER_DATA\"\nid = 0x200\nlength = 1\ncycle = \"20ms\"\n";
  EXPECT_EQ(said(canemuLoadCanNodes(taken, nullptr)),
            "invalid argument (can nodes:1: can_node OTHER: node ENGINE sends a message named "
            "\"ENGINE_DATA\" on \"can0\" already\n"
            "can nodes:1: can_node OTHER: node BRAKE sends identifier 0x200 on \"can0\" already "
            "(two senders of one identifier collide on the wire))");
  EXPECT_EQ(said(canemuLoadCanNodes("[[can_node]\n", nullptr)),
            "invalid argument (can nodes:1:12: Error while parsing table header: expected ']', "
            "saw '\\n')");
  EXPECT_EQ(nodes(), (Texts{"ENGINE can0 on 1 1", "BRAKE can0 on 1 0"}));
  clock_.to(26 * kMs);
  EXPECT_EQ(texts(alpha_.frames()),
            (Texts{sent(2, 0x120, engine_data(0, kTemp)), sent(5, 0x200, {0x00}),
                   sent(12, 0x120, engine_data(1, kTemp)), sent(22, 0x120, engine_data(2, kTemp)),
                   sent(25, 0x200, {0x00})}));
}

TEST_F(VciRestbus, PowerOffStopsANodeAndOnRestartsItsScheduleAtThatInstant) {
  clock_.to(15 * kMs);
  ASSERT_EQ(canemuPowerCanNode("ENGINE", FALSE), VCI_OK);
  EXPECT_EQ(nodes(), (Texts{"ENGINE can0 off 1 2", "BRAKE can0 on 1 1"}));
  clock_.to(40 * kMs);  // no ENGINE_DATA at 22 and 32 ms; its signals stay
  EXPECT_EQ(get("can0", "ENGINE_DATA.ENGINE_TEMP"), 85.5);
  ASSERT_EQ(canemuPowerCanNode("can0/ENGINE", TRUE), VCI_OK);  // BUS/NAME
  EXPECT_EQ(nodes(), (Texts{"ENGINE can0 on 1 2", "BRAKE can0 on 1 2"}));
  clock_.to(55 * kMs);  // from 40 ms: its delay (2 ms), then every 10 ms
  EXPECT_EQ(texts(alpha_.frames()),
            (Texts{sent(2, 0x120, engine_data(0, kTemp)), sent(5, 0x200, {0x00}),
                   sent(12, 0x120, engine_data(1, kTemp)), sent(25, 0x200, {0x00}),
                   sent(42, 0x120, engine_data(2, kTemp)), sent(45, 0x200, {0x00}),
                   sent(52, 0x120, engine_data(3, kTemp))}));
  EXPECT_EQ(nodes(), (Texts{"ENGINE can0 on 1 4", "BRAKE can0 on 1 3"}));
}

TEST_F(VciRestbus, ALoadReplacesANodeOfTheSameNameAndRemoveTakesItOff) {
  clock_.to(3 * kMs);
  // BRAKE again, sending from now (3 ms) with its delay of 5 ms: at 8 and 28 ms, not 5 and 25.
  const std::string tables(kTables);
  ASSERT_EQ(canemuLoadCanNodes(tables.substr(tables.find("[[can_node]]\nname = \"BRAKE\"")).c_str(),
                               "brake.toml"),
            VCI_OK)
      << said(VCI_E_INVALIDARG);
  EXPECT_EQ(nodes(), (Texts{"ENGINE can0 on 1 1", "BRAKE can0 on 1 0"}));
  clock_.to(15 * kMs);
  ASSERT_EQ(canemuRemoveCanNode("ENGINE"), VCI_OK);
  EXPECT_EQ(nodes(), (Texts{"BRAKE can0 on 1 1"}));
  EXPECT_EQ(said(canemuSetSignal("can0", "ENGINE_DATA.ENGINE_TEMP", 1)),
            "invalid argument (no simulated CAN node sends a message named \"ENGINE_DATA\" on "
            "can0)");
  EXPECT_EQ(said(canemuRemoveCanNode("ENGINE")),
            "invalid argument (no simulated CAN node named \"ENGINE\")");
  EXPECT_EQ(said(canemuPowerCanNode("ENGINE", TRUE)),
            "invalid argument (no simulated CAN node named \"ENGINE\")");
  clock_.to(30 * kMs);
  EXPECT_EQ(texts(alpha_.frames()),
            (Texts{sent(2, 0x120, engine_data(0, kTemp)), sent(8, 0x200, {0x00}),
                   sent(12, 0x120, engine_data(1, kTemp)), sent(28, 0x200, {0x00})}));
}

}  // namespace
}  // namespace canemu::testing
