// The frame half of the engine trace (engine_trace.hpp): random frames, and what their encoding
// shows.
#include <charconv>
#include <cstdarg>
#include <cstdio>

#include "canemu/firmware_model/bus/bit_timing.hpp"
#include "canemu/firmware_model/bus/wire_encoding.hpp"
#include "engine_trace.hpp"

namespace canemu::model::testing::engine_trace {

void appendf(std::string& out, const char* format, ...) {
  char buf[512];
  va_list args;
  va_start(args, format);
  const int n = std::vsnprintf(buf, sizeof buf, format, args);
  va_end(args);
  if (n < 0) {
    return;
  }
  if (static_cast<std::size_t>(n) < sizeof buf) {
    out.append(buf, static_cast<std::size_t>(n));
    return;
  }
  const std::size_t at = out.size();
  out.resize(at + static_cast<std::size_t>(n) + 1);
  va_start(args, format);
  std::vsnprintf(out.data() + at, static_cast<std::size_t>(n) + 1, format, args);
  va_end(args);
  out.resize(at + static_cast<std::size_t>(n));
}

namespace {

constexpr char kHex[] = "0123456789abcdef";

void append_uint(std::string& out, uint64_t v) {
  char buf[20];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  out.append(buf, r.ptr);
}

void append_hex64(std::string& out, uint64_t v) {
  char buf[16];
  for (int i = 15; i >= 0; --i) {
    buf[i] = kHex[v & 0xF];
    v >>= 4;
  }
  out.append(buf, 16);
}

// Bytes with long runs of equal bits, so that stuff bits are frequent.
constexpr std::array<uint8_t, 12> kRunBytes{0x00, 0xFF, 0x0F, 0xF0, 0x80, 0x7F,
                                            0x01, 0xFE, 0x55, 0xAA, 0x07, 0xE0};

uint8_t run_byte(Rng& rng) {
  return kRunBytes[rng.below(kRunBytes.size())];
}

void fill_data(Rng& rng, uint8_t* data, std::size_t length) {
  switch (rng.below(4)) {
    case 0: {  // one byte repeated
      const uint8_t b = run_byte(rng);
      for (std::size_t i = 0; i < length; ++i) {
        data[i] = b;
      }
      break;
    }
    case 1:  // bytes with runs
      for (std::size_t i = 0; i < length; ++i) {
        data[i] = run_byte(rng);
      }
      break;
    default:  // anything
      for (std::size_t i = 0; i < length; ++i) {
        data[i] = static_cast<uint8_t>(rng.next());
      }
      break;
  }
}

// Timings the durations are measured with: a CAN FD pair, and a nominal rate whose bit is not a
// whole number of ns with a data phase on another clock.
const BitTiming kNominal500k{80'000'000, 2, 63, 16, 16, 1};
const BitTiming kData2M{80'000'000, 2, 15, 4, 4, 1};
const BitTiming kNominal666k{16'000'000, 1, 17, 6, 2, 1};
const BitTiming kData5M{80'000'000, 1, 11, 4, 4, 1};

constexpr std::array<Field, 19> kAllFields{
    Field::sof,           Field::base_id,  Field::srr,           Field::ide,         Field::ext_id,
    Field::rtr,           Field::rrs,      Field::fdf,           Field::res,         Field::brs,
    Field::esi,           Field::dlc,      Field::data,          Field::stuff_count, Field::crc,
    Field::crc_delimiter, Field::ack_slot, Field::ack_delimiter, Field::eof};

// What the encoding of `f` shows within EncodedFrame's contract. `probe` picks the sampled
// positions (drawn apart from the frames, so that the frames do not depend on the encoding).
void trace_encoding(std::size_t index, const Frame& f, const EncodedFrame& e, Rng& probe,
                    std::string& out) {
  appendf(out, "f %zu ", index);
  append_frame(out, f);
  appendf(out, "\n len %u dyn %u fixed %u crc %x/%u arb %u crcdel %u bytes %u ext %d fd %d brs %d",
          e.length, e.dynamic_stuff_bits, e.fixed_stuff_bits, e.crc, e.crc_bits, e.arbitration_end,
          e.crc_delimiter_index, e.data_bytes, e.extended, e.fd, e.brs);
  if (e.fd) {
    appendf(out, " sc %u scb %u brsi %u", e.stuff_count, e.stuff_count_begin, e.brs_index);
  }
  out += "\n lv ";
  out += e.to_string();
  out += "\n st";
  for (uint16_t i = 0; i < e.length; ++i) {
    if (e.is_stuff(i)) {
      out += ' ';
      append_uint(out, i);
    }
  }
  out += "\n fields";
  std::array<FieldSpan, 19> spans;
  const uint8_t n = e.fields(spans);
  for (uint8_t i = 0; i < n; ++i) {
    out += ' ';
    out += to_string(spans[i].field);
    out += '@';
    append_uint(out, spans[i].begin);
  }
  // field_at and field_begin read fields() again at every call: sampled.
  out += "\n fa";
  for (int i = 0; i < 3; ++i) {
    const std::size_t bit = probe.below(e.length);
    appendf(out, " %zu:%s", bit, std::string(to_string(e.field_at(bit))).c_str());
  }
  const FieldSpan& edge = spans[probe.below(n)];
  if (edge.begin > 0) {
    appendf(out, " %u:%s", edge.begin - 1,
            std::string(to_string(e.field_at(edge.begin - 1u))).c_str());
  }
  appendf(out, " %u:%s", edge.begin, std::string(to_string(e.field_at(edge.begin))).c_str());
  out += "\n fb";
  appendf(out, " FDF:%u", e.field_begin(Field::fdf));
  for (int i = 0; i < 2; ++i) {
    const Field field = kAllFields[probe.below(kAllFields.size())];
    appendf(out, " %s:%u", std::string(to_string(field)).c_str(), e.field_begin(field));
  }
  // destuffed_index for every index up to the length, as the step from the one before ('1': a
  // data bit before it, '0': a stuff bit).
  out += "\n di ";
  uint16_t before = e.destuffed_index(0);
  append_uint(out, before);
  out += ':';
  for (uint16_t i = 1; i <= e.length; ++i) {
    const uint16_t d = e.destuffed_index(i);
    out += static_cast<char>('0' + (d - before));
    before = d;
  }  // stuffed_index on both sides of every dynamic stuff bit (where it steps by two), and at a few
  // destuffed bits drawn from the dynamically stuffed part (fields() above has it at every field).
  const uint16_t dynamic_end = e.fd ? e.stuff_count_begin : e.crc_delimiter_index;
  const uint16_t destuffed = static_cast<uint16_t>(dynamic_end - e.dynamic_stuff_bits);
  out += "\n si";
  auto stuffed = [&](uint16_t d) {
    out += ' ';
    append_uint(out, d);
    out += ':';
    append_uint(out, e.stuffed_index(d));
  };
  for (uint16_t i = 0, seen = 0; i < dynamic_end; ++i) {
    if (e.is_stuff(i)) {
      const auto d = static_cast<uint16_t>(i - seen);  // the first destuffed bit after it
      stuffed(static_cast<uint16_t>(d - 1));
      stuffed(d);
      ++seen;
    }
  }
  for (int i = 0; i < 3; ++i) {
    stuffed(static_cast<uint16_t>(probe.below(destuffed)));
  }
  const BitCounts bc = bit_counts(e);
  appendf(out, "\n bits %u+%u dur %lld %lld %lld", bc.nominal, bc.data,
          static_cast<long long>(frame_duration(e, kNominal500k, kData2M).ns()),
          static_cast<long long>(frame_duration(e, kNominal666k, kData5M).ns()),
          static_cast<long long>(frame_duration(e, kNominal666k).ns()));
  out += " pre";
  const std::array<uint32_t, 5> points{e.brs_index, e.brs_index + 1u, e.crc_delimiter_index,
                                       e.crc_delimiter_index + 1u,
                                       static_cast<uint32_t>(probe.below(e.length + 6u))};
  for (const uint32_t p : points) {
    appendf(out, " %u:%lld", p,
            static_cast<long long>(frame_prefix_duration(e, kNominal500k, kData2M, p).ns()));
  }
  out += '\n';
}

// Every word and field of `e` as the encoder left it: '-' for a word it left as the sentinel.
void trace_raw(const EncodedFrame& e, const EncodedFrame& sentinel, std::string& out) {
  auto words = [&](const char* name, const EncodedFrame::Bits& w, const EncodedFrame::Bits& s) {
    out += name;
    for (std::size_t i = 0; i < w.size(); ++i) {
      out += ' ';
      if (w[i] == s[i]) {
        out += '-';
      } else {
        append_hex64(out, w[i]);
      }
    }
  };
  words(" lv", e.level, sentinel.level);
  words(" st", e.stuff, sentinel.stuff);
  appendf(out, " | %u %u %u %x %u %u %d %d %u %u %u %d %u %u\n", e.length, e.dynamic_stuff_bits,
          e.fixed_stuff_bits, e.crc, e.crc_bits, e.stuff_count, e.fd, e.brs, e.brs_index,
          e.crc_delimiter_index, e.arbitration_end, e.extended, e.data_bytes, e.stuff_count_begin);
}

EncodedFrame make_sentinel() {
  EncodedFrame s;
  s.level.fill(0xA5A5A5A5A5A5A5A5ull);
  s.stuff.fill(0x5A5A5A5A5A5A5A5Aull);
  s.length = 0xEEEE;
  s.dynamic_stuff_bits = 0xEEEE;
  s.fixed_stuff_bits = 0xEEEE;
  s.crc = 0xEEEEEEEE;
  s.crc_bits = 0xEE;
  s.stuff_count = 0xEE;
  s.fd = true;
  s.brs = true;
  s.brs_index = 0xEEEE;
  s.crc_delimiter_index = 0xEEEE;
  s.arbitration_end = 0xEEEE;
  s.extended = true;
  s.data_bytes = 0xEE;
  s.stuff_count_begin = 0xEEEE;
  return s;
}

}  // namespace

void append_frame(std::string& out, const Frame& f) {
  appendf(out, "%0*x%s%s%s%s%s:%u", f.extended() ? 8 : 3, f.id(), f.extended() ? "x" : "",
          f.remote() ? "r" : "", f.fd() ? "f" : "", f.brs() ? "b" : "", f.esi() ? "e" : "",
          f.dlc());
  if (!f.data().empty()) {
    out += ':';
    for (const uint8_t b : f.data()) {
      out += kHex[b >> 4];
      out += kHex[b & 0xF];
    }
  }
}

Frame random_frame(Rng& rng) {
  FrameSpec spec;
  spec.fd = rng.chance(50);
  spec.extended = rng.chance(50);
  const uint32_t max = spec.extended ? kMaxExtendedId : kMaxStandardId;
  switch (rng.below(10)) {
    case 0:
      spec.id = 0;
      break;
    case 1:
      spec.id = max;
      break;
    case 2:
    case 3:
    case 4:
      spec.id = (uint32_t{run_byte(rng)} << 24 | uint32_t{run_byte(rng)} << 16 |
                 uint32_t{run_byte(rng)} << 8 | run_byte(rng)) &
                max;
      break;
    default:
      spec.id = static_cast<uint32_t>(rng.next()) & max;
      break;
  }
  if (spec.fd) {
    spec.brs = rng.chance(50);
    spec.esi = rng.chance(25);
  } else {
    spec.remote = rng.chance(15);
  }
  const auto dlc = static_cast<uint8_t>(rng.below(16));
  spec.dlc = dlc;
  std::array<uint8_t, kMaxFdLength> data{};
  const std::size_t length = spec.remote ? 0 : dlc_to_length(dlc, spec.fd);
  fill_data(rng, data.data(), length);
  spec.data = std::span<const uint8_t>(data.data(), length);
  return *Frame::create(spec);
}

void trace_frame_chunk(std::size_t k, std::string& text, std::string& raw, FrameCounts& counts) {
  using C = FrameCountNames::Id;
  const uint64_t seed = item_seed(kFrameSeed, k);
  Rng rng(seed);
  Rng probe(seed ^ 0x70726F6265ull);  // "probe"
  appendf(text, "chunk %zu seed 0x%016llx\n", k, static_cast<unsigned long long>(seed));
  appendf(raw, "chunk %zu seed 0x%016llx\n", k, static_cast<unsigned long long>(seed));
  static const EncodedFrame kSentinel = make_sentinel();
  const EncodedFrame kZero{};
  EncodedFrame e;
  for (std::size_t i = 0; i < kFramesPerChunk; ++i) {
    const std::size_t index = k * kFramesPerChunk + i;
    const Frame f = random_frame(rng);
    e = kSentinel;
    encode(f, e);
    trace_encoding(index, f, e, probe, text);
    appendf(raw, "f %zu", index);
    trace_raw(e, kSentinel, raw);
    // The encoding returned by value starts from zeros.
    raw += " v";
    trace_raw(encode(f), kZero, raw);

    counts[C::frames]++;
    counts[f.fd() ? C::fd : C::classic]++;
    counts[C::extended] += f.extended();
    counts[C::remote] += f.remote();
    counts[C::classic_dlc_over_8] += !f.fd() && f.dlc() > 8;
    counts[C::brs] += f.brs();
    counts[C::esi] += f.esi();
    counts[C::fd_over_16_bytes] += f.fd() && f.length() > 16;
    counts[C::fd_64_bytes] += f.fd() && f.length() == 64;
    counts[C::extended_fd_64_bytes] += f.fd() && f.length() == 64 && f.extended();
    counts[C::stuff_bits] += e.dynamic_stuff_bits;
  }
}

}  // namespace canemu::model::testing::engine_trace
