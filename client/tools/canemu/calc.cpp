// canemu calc: offline calculations on the wire model: a CAN frame's exact bits and duration, a
// LIN frame's fields and times, and the bit timing of SJA1000 BTR0/BTR1 values.
#include <array>
#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <CLI/CLI.hpp>

#include "canemu/firmware_model/bus/bit_timing.hpp"
#include "canemu/firmware_model/bus/lin_frame.hpp"
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

// A LIN frame as ID#DATA: a hex identifier 0..3F, then up to 8 data bytes in hex (none: a
// header alone).
struct LinText {
  uint8_t id = 0;
  std::vector<uint8_t> data;
};

std::optional<LinText> parse_lin(const std::string& text, std::string& error) {
  const auto hash = text.find('#');
  const std::string id_text = text.substr(0, hash);
  const std::string data_text = hash == std::string::npos ? "" : text.substr(hash + 1);
  unsigned id = 0;
  if (id_text.empty() || id_text.size() > 2 ||
      id_text.find_first_not_of("0123456789abcdefABCDEF") != std::string::npos ||
      (id = static_cast<unsigned>(std::stoul(id_text, nullptr, 16))) > model::lin::kMaxId) {
    error = "the identifier is hex 0..3F";
    return std::nullopt;
  }
  if (data_text.size() % 2 != 0 || data_text.size() > 2 * model::lin::kMaxData) {
    error = "the data are 1 to 8 bytes of two hex digits each";
    return std::nullopt;
  }
  LinText out;
  out.id = static_cast<uint8_t>(id);
  for (std::size_t k = 0; k < data_text.size(); k += 2) {
    const auto byte = parse_register(data_text.substr(k, 2));
    if (!byte) {
      error = fmt::format("'{}' is not a hex byte", data_text.substr(k, 2));
      return std::nullopt;
    }
    out.data.push_back(*byte);
  }
  return out;
}

struct LinOptions {
  std::string frame;
  uint32_t bitrate = 19200;
  bool classic = false;
  model::lin::Layout layout;
};

int run_lin(const LinOptions& o) {
  namespace lin = model::lin;
  std::string error;
  const auto f = parse_lin(o.frame, error);
  if (!f) {
    return fail(
        fmt::format("'{}': {} (examples: 10#1122, 3C#0000000000000000, 21 for a header "
                    "alone)",
                    o.frame, error));
  }
  lin::Layout layout = o.layout;
  layout.bitrate = o.bitrate;
  const auto n = static_cast<uint32_t>(f->data.size());
  const lin::FrameBits bits = lin::frame_bits(layout, n);
  const uint8_t pid = lin::protected_id(f->id);
  std::printf("break    %u dominant bits, delimiter %u recessive bit%s\n", layout.break_bits,
              layout.delimiter_bits, layout.delimiter_bits == 1 ? "" : "s");
  std::printf("sync     0x%02X\n", lin::kSyncByte);
  std::printf("PID      0x%02X (ID 0x%02X, parity P0 %u P1 %u)\n", pid, f->id, (pid >> 6) & 1u,
              (pid >> 7) & 1u);
  const auto ns = [&](uint64_t b) {
    return static_cast<long long>(lin::bits_duration(b, o.bitrate).ns());
  };
  if (n == 0) {
    std::printf("bits: header %u\nat %u bit/s: header %lld ns\n", bits.header_end, o.bitrate,
                ns(bits.header_end));
    return 0;
  }
  std::string data;
  for (uint8_t b : f->data) {
    data += fmt::format("{:02X} ", b);
  }
  data.pop_back();
  const auto kind =
      lin::effective_checksum(o.classic ? lin::Checksum::classic : lin::Checksum::enhanced, f->id);
  std::printf("data     %s\n", data.c_str());
  std::printf("checksum 0x%02X (%s)\n", lin::checksum(kind, f->id, f->data),
              kind == lin::Checksum::enhanced ? "enhanced" : "classic");
  std::printf("bits: %u (header %u, response %u)\n", bits.response_end, bits.header_end,
              bits.response_end - bits.header_end);
  std::printf("at %u bit/s: %lld ns (header %lld ns); nominal %lld ns, at most %lld ns (1.4 x)\n",
              o.bitrate, ns(bits.response_end), ns(bits.header_end),
              ns(lin::kNominalHeaderBits + lin::nominal_response_bits(n)),
              static_cast<long long>(lin::maximum_frame_duration(n, o.bitrate).ns()));
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
  auto l = std::make_shared<LinOptions>();
  auto* lin = calc->add_subcommand("lin", "a LIN frame's fields and exact times, e.g. 10#1122");
  lin->add_option("FRAME", l->frame, "ID#DATA in hex: 10#1122; an ID alone for a header")
      ->required();
  lin->add_option("--bitrate", l->bitrate, "bit/s, 1000..20000 (default 19200)")
      ->check(CLI::Range(1'000u, 20'000u));
  lin->add_flag("--classic", l->classic, "the classic checksum (LIN 1.x; default enhanced)");
  lin->add_option("--break-bits", l->layout.break_bits, "dominant bits of the break, 13..30")
      ->check(CLI::Range(13u, 30u));
  lin->add_option("--delimiter-bits", l->layout.delimiter_bits, "break delimiter, 1..14 bits")
      ->check(CLI::Range(1u, 14u));
  lin->add_option("--interbyte-bits", l->layout.interbyte_bits,
                  "space between characters, 0..10 bits")
      ->check(CLI::Range(0u, 10u));
  lin->add_option("--response-space-bits", l->layout.response_space_bits,
                  "space between header and response, 0..10 bits")
      ->check(CLI::Range(0u, 10u));
  return {calc, [o, l, frame, bt, lin] {
            if (*frame) {
              return run_frame(o->frame, o->bitrate, o->data_bitrate);
            }
            if (*lin) {
              return run_lin(*l);
            }
            if (*bt) {
              return run_bittiming(o->btr0, o->btr1);
            }
            return 1;
          }};
}

}  // namespace canemu::cli
