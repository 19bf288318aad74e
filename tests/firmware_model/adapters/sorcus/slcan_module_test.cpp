// The SL-CANi's driver task at the level of its calls: the EEPROM, the configuration order,
// message objects and their rules, the diagnosis codes, the acceptance mask, the LED and the
// faults (digest §6 items 4, 19, 21, 24-30, 32, 40, 41, 58, 59, 63, 64, 72, 75, 77, 79, 86, 103,
// 104). Bus behaviour is in slcan_bus_test.cpp.
#include <gtest/gtest.h>

#include "adapters/sorcus/slcan_fixture.hpp"
#include "case_name.hpp"

namespace canemu::model::sorcus {
namespace {

using namespace testing;
using Bytes = std::vector<uint8_t>;

TEST(SlcanEeprom, HoldsTheManualsFactoryContents) {
  // Words 0 to 19; the rest are 0.
  const EepromWords expected{0x534C, 0x0040, 0x0002, 0x0001, 0x0005, 0x0021, 0,
                             0,      0,      0,      0,      0,      0x0010, 0x0007,
                             0,      0x09C4, 0x0010, 0x0003, 0x0002, 0x0001};
  EXPECT_EQ(slcan_eeprom_defaults(), expected);
}

TEST(SlcanEeprom, OnlyWords13To19And32To63AreWritable) {
  SlcanLog log;
  SimScheduler sched;
  SlcanModule m(sched, 0, log);
  for (unsigned w = 0; w < 64; ++w) {
    const bool writable = (w >= 13 && w <= 19) || w >= 32;
    EXPECT_EQ(m.write_eeprom(w, 0x1234), writable) << "word " << w;
    EXPECT_EQ(m.eeprom()[w], writable ? 0x1234 : slcan_eeprom_defaults()[w]) << "word " << w;
  }
  EXPECT_FALSE(m.write_eeprom(64, 1));
}

// EEPROM contents the driver accepts, as changes to the factory words, and the settings they
// give: the timing on the 10 MHz clock (prescaler in 100 ns steps), termination and format.
struct Accepted {
  const char* name;
  std::vector<std::pair<unsigned, uint16_t>> words;
  uint32_t prescaler;
  uint32_t tseg1;
  uint32_t tseg2;
  uint32_t sjw;
  uint32_t bit_100ns;  // the bit time in 100 ns steps
  bool termination;
  bool extended;
};

class SlcanEepromAccepts : public ::testing::TestWithParam<Accepted> {};

TEST_P(SlcanEepromAccepts, TheSettingsTheWordsGive) {
  const Accepted& c = GetParam();
  EepromWords w = slcan_eeprom_defaults();
  for (const auto& [word, value] : c.words) {
    w[word] = value;
  }
  const auto s = slcan_settings(w);
  ASSERT_TRUE(s.has_value()) << s.error().why;
  EXPECT_EQ(s->timing.clock_hz, 10'000'000u);
  EXPECT_EQ(s->timing.prescaler, c.prescaler);
  EXPECT_EQ(s->timing.tseg1, c.tseg1);
  EXPECT_EQ(s->timing.tseg2, c.tseg2);
  EXPECT_EQ(s->timing.sjw, c.sjw);
  EXPECT_EQ(s->timing.quanta_per_bit() * s->timing.prescaler, c.bit_100ns);
  EXPECT_EQ(s->termination, c.termination);
  EXPECT_EQ(s->extended, c.extended);
}

INSTANTIATE_TEST_SUITE_P(
    SlcanEeprom, SlcanEepromAccepts,
    ::testing::Values(
        // 2500 ns quanta, 16 + 3 + 1: 50 µs, 20 kbit/s.
        Accepted{"TheFactoryTimingIs20KbitWithoutTermination", {}, 25, 16, 3, 2, 500, false, false},
        Accepted{"Words13And14GiveTerminationAndTheIdentifierFormat",
                 {{13, 0x000F}, {14, 0x0001}},
                 25,
                 16,
                 3,
                 2,
                 500,
                 true,
                 true},
        // 400 ns, 16, 2, 1: (16 + 2 + 1) x 400 ns = 7.6 µs, 131.58 kbit/s, not 125 (digest §7.5).
        Accepted{"The125KbitTableRowGivesWhatItsParametersGive",
                 {{15, 400}, {16, 16}, {17, 2}, {18, 1}},
                 4,
                 16,
                 2,
                 1,
                 76,
                 false,
                 false}),
    test_support::CaseName{});

TEST(SlcanEeprom, EachOutOfRangeWordGivesItsDiagnosisNamingTheWord) {
  struct Case {
    unsigned word;
    uint16_t value;
    uint16_t diagnosis;
    const char* named;
  };
  for (const Case& c :
       {Case{12, 0x0016, 0x31, "word 12"}, Case{13, 0x0003, 0x24, "word 13"},
        Case{14, 0x0002, 0x24, "word 14"}, Case{15, 99, 0x24, "Tq"}, Case{15, 6500, 0x24, "Tq"},
        Case{15, 150, 0x24, "multiple"}, Case{16, 2, 0x24, "Tseg1"}, Case{17, 9, 0x24, "Tseg2"},
        Case{18, 5, 0x24, "Tsjw"}, Case{19, 2, 0x24, "samples"},
        Case{18, 4, 0x24, "Tseg2 = 3 is less than Tsjw = 4"}}) {
    EepromWords w = slcan_eeprom_defaults();
    w[c.word] = c.value;
    const auto s = slcan_settings(w);
    ASSERT_FALSE(s.has_value()) << c.word;
    EXPECT_EQ(s.error().diagnosis, c.diagnosis) << c.word;
    EXPECT_NE(s.error().why.find(c.named), std::string::npos) << s.error().why;
  }
}

TEST(SlcanModule, ConfigModuleChecksTheEepromWith31hAnd24h) {
  Slcan x;
  EepromWords w = x.m.eeprom();
  w[12] = 0x0020;  // a state file that says otherwise: word 12 is read-only for programs
  x.m.load_eeprom(w);
  EXPECT_EQ(x.m.bib_startup(), 0);
  EXPECT_EQ(x.diag(x.m.config_module(0, 0)), error(0x31));
  w[12] = 0x0010;
  w[17] = 1;
  x.m.load_eeprom(w);
  EXPECT_EQ(x.diag(x.m.config_module(0, 0)), error(0x24));
  EXPECT_FALSE(x.m.configured());
  w[17] = 3;
  x.m.load_eeprom(w);
  EXPECT_EQ(x.diag(x.m.config_module(0, 0)), kOk);
  EXPECT_TRUE(x.m.configured());
}

TEST(SlcanModule, EveryCallOutOfTheConfigurationOrderGives2Dh) {
  Slcan x;
  SL064Handle h = 0;
  SL064MsgType c{7, _SL064_SEND | _SL064_ACTIVE, 0, 0};
  ULONG mask = 0;
  const Diag order = error(0x2D);
  // Before sl064_bib_startup.
  EXPECT_EQ(x.diag(x.m.config_module(0, 0)), order);
  // Before sl064_config_module.
  EXPECT_EQ(x.diag(x.m.bib_startup()), kOk);
  EXPECT_EQ(x.diag(x.m.config_msg_object(c, h)), order);
  EXPECT_EQ(h, 0);
  EXPECT_EQ(x.diag(x.m.set_acceptance_mask(mask, 0, 0, 0)), order);
  EXPECT_EQ(x.diag(x.m.start_com()), order);
  EXPECT_EQ(x.diag(x.m.clear_configuration()), order);
  // sl064_config_module twice.
  EXPECT_EQ(x.diag(x.m.config_module(0, 0)), kOk);
  EXPECT_EQ(x.diag(x.m.config_module(0, 0)), order);
  // Sending before sl064_start_com.
  h = x.object(7, _SL064_SEND | _SL064_ACTIVE);
  EXPECT_EQ(x.diag(x.m.send_data(h)), order);
  // An object after the acceptance mask; the mask twice.
  EXPECT_EQ(x.diag(x.m.set_acceptance_mask(mask, 0, 0, 0)), kOk);
  EXPECT_EQ(x.diag(x.m.set_acceptance_mask(mask, 0, 0, 0)), order);
  c.id = 8;
  EXPECT_EQ(x.diag(x.m.config_msg_object(c, h)), order);
  EXPECT_EQ(h, 0);
  // start_com; then an object, the mask or start_com again.
  EXPECT_EQ(x.diag(x.m.start_com()), kOk);
  EXPECT_EQ(x.diag(x.m.start_com()), order);
  EXPECT_EQ(x.diag(x.m.config_msg_object(c, h)), order);
  EXPECT_EQ(x.m.object_count(), 1u);
}

TEST(SlcanModule, ObjectsGetHandlesFrom1AndStartWithAnEmptyPayload) {
  Slcan x;
  x.configure();
  // The manual's example: slot 1, ID 7, send active and passive, routine task 100 function 4.
  const SL064Handle h1 = x.object(7, _SL064_SEND | _SL064_ACTIVE | _SL064_PASSIVE);
  const SL064Handle h2 = x.object(8, _SL064_PASSIVE);
  EXPECT_EQ(h1, 1);
  EXPECT_EQ(h2, 2);
  std::array<uint8_t, 8> d{};
  d.fill(0xEE);
  uint8_t size = 0;
  EXPECT_EQ(x.diag(x.m.get_data(h1, d, size)), kOk);
  EXPECT_EQ(size, 0);
  EXPECT_EQ(d, (std::array<uint8_t, 8>{}));
  ULONG id = 0;
  EXPECT_EQ(x.diag(x.m.get_id(h2, id)), kOk);
  EXPECT_EQ(id, 8u);
  ULONG count = 99;
  EXPECT_EQ(x.diag(x.m.get_msg_count(h1, count)), kOk);
  EXPECT_EQ(count, 0u);
  EXPECT_EQ(x.m.buffer(1).use, BufferView::Use::own);
  EXPECT_EQ(x.m.buffer(1).id, 7u);
  EXPECT_EQ(x.m.buffer(2).id, 8u);
}

TEST(SlcanModule, TheRoleFlagsAndTheIdentifierRangeAreChecked) {
  Slcan x;
  x.configure();
  USHORT d = 0;
  struct Case {
    ULONG id;
    USHORT flags;
    USHORT diagnosis;
  };
  for (const Case& c : {
           Case{1, _SL064_SEND, 0x2A},                         // a send object needs a role
           Case{2, 0, 0x2A},                                   // so does a receive object
           Case{3, _SL064_EXCL_BUFFER, 0x2A},                  // EXCL is no role
           Case{4, _SL064_DISABLE_INT | _SL064_ACTIVE, 0x2A},  // DISABLE_INT: send objects only
           Case{5, 0x0100 | _SL064_ACTIVE, 0x2A},              // no such flag
           Case{2032, _SL064_PASSIVE, 0x2A},                   // beyond 2031
           Case{2031, _SL064_PASSIVE, 0},
           Case{0, _SL064_SEND | _SL064_DISABLE_INT, 0},   // always active and passive
           Case{2031, _SL064_SEND | _SL064_ACTIVE, 0x28},  // the same ID twice
       }) {
    const SL064Handle h = x.object(c.id, c.flags, &d);
    EXPECT_EQ(d, c.diagnosis) << "id " << c.id << " flags " << c.flags;
    EXPECT_EQ(h == 0, c.diagnosis != 0) << "id " << c.id;
  }
  EXPECT_EQ(x.m.object_count(), 2u);
}

TEST(SlcanModule, Eeprom29BitFormatAllowsIdentifiersUpTo268435447) {
  Slcan x;
  ASSERT_TRUE(x.m.write_eeprom(SL064_EEPROM_ID_FORMAT, 1));
  x.configure();
  USHORT d = 0;
  EXPECT_EQ(x.object(268435447, _SL064_PASSIVE, &d), 1);
  EXPECT_EQ(d, 0);
  EXPECT_EQ(x.object(268435448, _SL064_PASSIVE, &d), 0);
  EXPECT_EQ(d, 0x2A);
}

TEST(SlcanModule, AFourteenthExclusiveBufferGives27h) {
  Slcan x;
  x.configure();
  for (ULONG id = 1; id <= 13; ++id) {
    x.object(id, _SL064_SEND | _SL064_ACTIVE | _SL064_EXCL_BUFFER);
  }
  USHORT d = 0;
  EXPECT_EQ(x.object(14, _SL064_PASSIVE | _SL064_EXCL_BUFFER, &d), 0);
  EXPECT_EQ(d, 0x27);
  // Without EXCL it is fine.
  EXPECT_EQ(x.object(14, _SL064_PASSIVE), 14);
}

TEST(SlcanModule, PassiveSendAndReceiveObjectsWithoutExclInBuffer15Give2Ch) {
  Slcan x;
  x.configure();
  for (ULONG id = 1; id <= 7; ++id) {
    x.object(id, _SL064_SEND | _SL064_PASSIVE);
    x.object(0x100 + id, _SL064_PASSIVE);
  }
  // 14 objects: each its own buffer. The 15th makes buffer 15 needed for both kinds.
  USHORT d = 0;
  EXPECT_EQ(x.object(0x200, _SL064_PASSIVE, &d), 0);
  EXPECT_EQ(d, 0x2C);
  // Any 15th object would put the 14 passive ones into buffer 15: also an active one.
  EXPECT_EQ(x.object(0x200, _SL064_SEND | _SL064_ACTIVE, &d), 0);
  EXPECT_EQ(d, 0x2C);
  EXPECT_EQ(x.m.object_count(), 14u);
  EXPECT_EQ(x.m.buffer(15).use, BufferView::Use::unused);
}

TEST(SlcanModule, Buffer15TakesThePassiveObjectsBehindTheirAutomaticFilter) {
  Slcan x;
  x.configure();
  x.object(0x03, _SL064_PASSIVE);
  x.object(0x07, _SL064_PASSIVE);
  for (ULONG id = 0x400; id < 0x40D; ++id) {
    x.object(id, _SL064_SEND | _SL064_ACTIVE);  // active only: never in buffer 15
  }
  EXPECT_EQ(x.m.object_count(), 15u);
  EXPECT_EQ(x.m.buffer(15).use, BufferView::Use::receive_only);
  EXPECT_EQ(x.m.buffer15_filter(), (AcceptanceFilter{0x7FB, 0x003}));
}

TEST(SlcanModule, MoreThanThePlannedObjectsGive21h) {
  Slcan x;
  x.configure();
  for (ULONG id = 0; id < SlcanModule::kMaxObjects; ++id) {
    x.object(id, _SL064_SEND | _SL064_ACTIVE);
  }
  USHORT d = 0;
  EXPECT_EQ(x.object(1500, _SL064_SEND | _SL064_ACTIVE, &d), 0);
  EXPECT_EQ(d, 0x21);
}

TEST(SlcanModule, ARoutineNotInstalledIsWarning2AndTheDiagnosisIsResetWhenRead) {
  Slcan x;
  EXPECT_EQ(x.m.bib_startup(), 0);
  EXPECT_EQ(x.diag(x.m.config_module(kTask, 77)), warning(2));
  USHORT d = 0;
  EXPECT_EQ(x.object(7, _SL064_PASSIVE, &d, 200, 1), 1);
  EXPECT_EQ(d, 2);
  // Function 14 of this slot's SL64TASK (task 41h) is always there.
  EXPECT_EQ(x.object(8, _SL064_PASSIVE, &d, 0x41, SL064_SRQ_SERVICE_FUNC), 2);
  EXPECT_EQ(d, 0);
  EXPECT_EQ(x.object(8, _SL064_PASSIVE, &d), 0);
  EXPECT_EQ(x.m.get_diagnosis(), 0);  // read once by object(): reset to 0
  EXPECT_EQ(d, 0x28);
}

TEST(SlcanModule, DataCallsCheckTheObjectsType) {
  Slcan x;
  x.configure();
  const SL064Handle active_send = x.object(1, _SL064_SEND | _SL064_ACTIVE);
  const SL064Handle passive_send = x.object(2, _SL064_SEND | _SL064_PASSIVE);
  const SL064Handle active_receive = x.object(3, _SL064_ACTIVE);
  const SL064Handle passive_receive = x.object(4, _SL064_PASSIVE);
  ASSERT_EQ(x.diag(x.m.start_com()), kOk);
  const Diag wrong = error(0x2A);
  EXPECT_EQ(x.diag(x.set(active_receive, {1})), wrong);
  EXPECT_EQ(x.diag(x.set(passive_receive, {1})), wrong);
  EXPECT_EQ(x.diag(x.set(active_send, {1, 2, 3, 4, 5, 6, 7, 8, 9})), wrong);
  EXPECT_EQ(x.diag(x.set(passive_send, {1, 2})), kOk);
  EXPECT_EQ(x.diag(x.m.send_data(passive_send)), wrong);
  EXPECT_EQ(x.diag(x.m.send_data(active_receive)), wrong);
  EXPECT_EQ(x.diag(x.m.send_data_request(active_send)), wrong);
  EXPECT_EQ(x.diag(x.m.send_data_request(passive_receive)), wrong);
  EXPECT_EQ(x.diag(x.m.send_data(0)), wrong);
  EXPECT_EQ(x.diag(x.m.send_data(5)), wrong);
  EXPECT_EQ(x.diag(x.m.clear_msg(5)), wrong);
  // get_data: in = wanted, out = delivered; a mismatch is warning 1.
  std::array<uint8_t, 8> d{};
  uint8_t size = 8;
  EXPECT_EQ(x.diag(x.m.get_data(passive_send, d, size)), warning(1));
  EXPECT_EQ(size, 2);
  EXPECT_EQ(d[0], 1);
  EXPECT_EQ(d[1], 2);
  size = 2;
  EXPECT_EQ(x.diag(x.m.get_data(passive_send, d, size)), kOk);
}

TEST(SlcanModule, ClearConfigurationDeletesEveryObjectAndNeedsStartComAgain) {
  Slcan x;
  x.configure();
  const SL064Handle a = x.object(1, _SL064_SEND | _SL064_ACTIVE);
  x.object(2, _SL064_PASSIVE);
  ULONG mask = 0x7F0;
  ASSERT_EQ(x.diag(x.m.set_acceptance_mask(mask, 0, 0, 0)), kOk);
  ASSERT_EQ(x.diag(x.m.start_com()), kOk);
  EXPECT_EQ(x.diag(x.m.clear_configuration()), kOk);
  EXPECT_FALSE(x.m.running());
  EXPECT_EQ(x.m.object_count(), 0u);
  EXPECT_EQ(x.diag(x.m.send_data(a)), error(0x2D));  // communication is off
  // No config_module again; the old handles stay invalid, new ones follow them; the mask may
  // be set again.
  const SL064Handle b = x.object(1, _SL064_SEND | _SL064_ACTIVE);
  EXPECT_EQ(b, 3);
  EXPECT_EQ(x.diag(x.m.set_data(a, {})), error(0x2A));
  EXPECT_EQ(x.diag(x.m.set_acceptance_mask(mask, 0, 0, 0)), kOk);
  EXPECT_EQ(x.diag(x.m.start_com()), kOk);
  EXPECT_EQ(x.diag(x.m.send_data(b)), kOk);
}

TEST(SlcanModule, TheAcceptanceMaskMayNotLockOutConfiguredMessages) {
  Slcan x;
  x.configure();
  for (ULONG id = 0x100; id <= 0x10E; ++id) {
    x.object(id, _SL064_PASSIVE);  // 15 objects: all in buffer 15, automatic mask 7F0h
  }
  ASSERT_EQ(x.m.buffer15_filter(), (AcceptanceFilter{0x7F0, 0x100}));
  ULONG mask = 0x7FF;
  EXPECT_EQ(x.diag(x.m.set_acceptance_mask(mask, 0, kTask, kFunc)), error(0x29));
  EXPECT_EQ(mask, 0x7FFu);  // unchanged
  mask = 0x700;
  EXPECT_EQ(x.diag(x.m.set_acceptance_mask(mask, 1, kTask, kFunc)), error(0x29));  // remote
  EXPECT_EQ(x.diag(x.m.set_acceptance_mask(mask, 0, kTask, kFunc)), kOk);
  EXPECT_EQ(mask, 0x700u);
}

TEST(SlcanModule, TheLedIsSetAndReadBack) {
  Slcan x;
  EXPECT_EQ(x.m.get_led(), 0);
  x.m.set_led(1);
  EXPECT_EQ(x.m.get_led(), 1);
  x.m.set_led(0);
  EXPECT_EQ(x.m.get_led(), 0);
}

TEST(SlcanModule, HardwareFaultsGiveTheirDiagnosis) {
  struct Case {
    SlcanFault fault;
    USHORT startup;
    USHORT config;
  };
  for (const Case& c :
       {Case{SlcanFault::no_response, 0x22, 0x22}, Case{SlcanFault::reset, 0, 0x2E},
        Case{SlcanFault::async_init, 0x2F, 0x2F}, Case{SlcanFault::sync_init, 0x30, 0x30},
        Case{SlcanFault::no_m6p0500, 0x32, 0x32}, Case{SlcanFault::m6p0500_error, 0x33, 0x33},
        Case{SlcanFault::scc_frequency, 0x35, 0x35}}) {
    Slcan x;
    x.m.set_fault(c.fault);
    EXPECT_EQ(x.diag(x.m.bib_startup()), c.startup ? error(c.startup) : kOk);
    EXPECT_EQ(x.diag(x.m.config_module(0, 0)), error(c.config));
    x.m.set_fault(SlcanFault::none);
    EXPECT_EQ(x.diag(x.m.bib_startup()), kOk);
    EXPECT_EQ(x.diag(x.m.config_module(0, 0)), kOk);
  }
}

TEST(SlcanModule, TheServiceRequestWordIs80hWithTheSlotInTheHighByte) {
  EXPECT_EQ(SL064_SRQ_WORD(0), 0x0080);
  EXPECT_EQ(SL064_SRQ_WORD(5), 0x0580);
}

}  // namespace
}  // namespace canemu::model::sorcus
