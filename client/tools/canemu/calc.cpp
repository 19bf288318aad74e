// canemu calc: offline calculations on the wire model: a frame's exact bits and duration, and
// the bit timing of SJA1000 BTR0/BTR1 values.
#include <array>
#include <cstdio>
#include <memory>
#include <optional>
#include <string>

#include <fmt/format.h>
#include <CLI/CLI.hpp>

#include "canemu/firmware_model/bus/bit_timing.hpp"
#include "canemu/firmware_model/bus/wire_encoding.hpp"
#include "canemu/firmware_model/chips/sja1000/btr.hpp"
#include "command.hpp"
#include "frame_text.hpp"

namespace canemu::cli {

namespace {

int run_frame(const std::string& text, uint32_t bitrate, uint32_t data_bitrate) {
  std::string error;
  auto message = parse_cansend(text, error);
  if (!message) {
    return fail(fmt::format("'{}': {}", text, error));
  }
  const model::EncodedFrame e = model::encode(*to_frame(*message));
  std::array<model::FieldSpan, 19> fields;
  const uint8_t n = e.fields(fields);
  for (uint8_t k = 0; k < n; ++k) {
    const uint16_t end = k + 1 < n ? fields[k + 1].begin : e.length;
    std::string bits;
    for (uint16_t i = fields[k].begin; i < end; ++i) {
      bits += e.is_stuff(i) ? (e.level_at(i) ? "[1]" : "[0]") : (e.level_at(i) ? "1" : "0");
    }
    std::printf("%-8s %s\n", std::string(model::to_string(fields[k].field)).c_str(), bits.c_str());
  }
  const model::BitCounts counts = model::bit_counts(e);
  std::printf("bits: %u (+%u intermission), stuff bits: %u dynamic, %u fixed; CRC-%u 0x%X\n",
              e.length, model::kIntermissionBits, e.dynamic_stuff_bits, e.fixed_stuff_bits,
              e.crc_bits, e.crc);
  if (bitrate == 0 || data_bitrate == 0) {
    return fail("bit rates must be above 0");
  }
  // Durations depend only on the rates: ten quanta per bit at exactly that rate.
  const auto at_rate = [](uint32_t bps) {
    return model::BitTiming{uint64_t{bps} * 10, 1, 7, 2, 1, 1};
  };
  const auto nominal = std::optional<model::BitTiming>(at_rate(bitrate));
  const auto data = std::optional<model::BitTiming>(at_rate(data_bitrate));
  std::printf(
      "at %u bit/s%s: %lld ns (%u nominal + %u data-phase bits), %lld ns with "
      "intermission\n",
      bitrate, e.brs ? fmt::format(" / {} bit/s", data_bitrate).c_str() : "",
      static_cast<long long>(model::frame_duration(e, *nominal, *data).ns()), counts.nominal,
      counts.data,
      static_cast<long long>(
          (model::frame_duration(e, *nominal, *data) + model::intermission_duration(*nominal))
              .ns()));
  return 0;
}

// A register value in hex: one or two digits, optionally after 0x.
std::optional<uint8_t> parse_register(std::string text) {
  if (text.size() > 2 && text[0] == '0' && (text[1] == 'x' || text[1] == 'X')) {
    text = text.substr(2);
  }
  if (text.empty() || text.size() > 2) {
    return std::nullopt;
  }
  unsigned value = 0;
  for (char ch : text) {
    const int digit = ch >= '0' && ch <= '9'   ? ch - '0'
                      : ch >= 'a' && ch <= 'f' ? ch - 'a' + 10
                      : ch >= 'A' && ch <= 'F' ? ch - 'A' + 10
                                               : -1;
    if (digit < 0) {
      return std::nullopt;
    }
    value = value * 16 + static_cast<unsigned>(digit);
  }
  return static_cast<uint8_t>(value);
}

int run_bittiming(const std::string& btr0_text, const std::string& btr1_text) {
  const auto btr0 = parse_register(btr0_text);
  const auto btr1 = parse_register(btr1_text);
  if (!btr0 || !btr1) {
    return fail(
        fmt::format("'{}' is not a register value: BTR0 and BTR1 are two hex digits each "
                    "(example: canemu calc bittiming 00 1C)",
                    !btr0 ? btr0_text : btr1_text));
  }
  const auto t = model::sja1000::decode_btr(*btr0, *btr1);
  if (!t) {
    return fail(t.error().message);
  }
  std::printf(
      "SJA1000 at 16 MHz: %.3f bit/s, tq %.3f ns, %u quanta (1 + %u + %u), sample point "
      "%.1f %%, SJW %u, %u sample%s per bit\n",
      t->bit_rate().bps(), static_cast<double>(t->quantum_ps()) / 1000.0, t->quanta_per_bit(),
      t->tseg1, t->tseg2, t->sample_point_permille() / 10.0, t->sjw, t->samples,
      t->samples == 1 ? "" : "s");
  return 0;
}

struct CalcOptions {
  std::string frame;
  uint32_t bitrate = 500000;
  uint32_t data_bitrate = 2000000;
  std::string btr0, btr1;
};

}  // namespace

Command add_calc(CLI::App& app) {
  auto* calc = app.add_subcommand("calc", "offline calculations on the wire model");
  calc->require_subcommand(1);
  auto o = std::make_shared<CalcOptions>();
  auto* frame = calc->add_subcommand("frame", "exact bits and duration of a frame, e.g. 123#1122");
  frame->add_option("FRAME", o->frame, "cansend syntax: 123#1122, 12345678#R, 123##1AABB")
      ->required();
  // The ranges canemud accepts for a bus (docs/configuration.md).
  frame->add_option("--bitrate", o->bitrate, "nominal bit/s, 5000..1000000 (default 500000)")
      ->check(CLI::Range(5'000u, 1'000'000u));
  frame
      ->add_option("--data-bitrate", o->data_bitrate,
                   "data-phase bit/s for BRS, up to 10000000 (default 2000000)")
      ->check(CLI::Range(5'000u, 10'000'000u));
  auto* bt = calc->add_subcommand("bittiming", "decode SJA1000 BTR0 BTR1 (hex), e.g. 00 1C");
  bt->add_option("BTR0", o->btr0, "hex")->required();
  bt->add_option("BTR1", o->btr1, "hex")->required();
  return {calc, [o, frame, bt] {
            if (*frame) {
              return run_frame(o->frame, o->bitrate, o->data_bitrate);
            }
            if (*bt) {
              return run_bittiming(o->btr0, o->btr1);
            }
            return 1;
          }};
}

}  // namespace canemu::cli
