// Encoding throughput of the wire model: frames encoded per second on one core, bit-exact
// (stuffing, CRC, field map). Target: over 5 million classic 8-byte frames/s.
#include <benchmark/benchmark.h>

#include <random>
#include <vector>

#include "canemu/firmware_model/bus/wire_encoding.hpp"
#include "canemu/firmware_model/chips/sja1000/btr.hpp"

namespace {

using namespace canemu::model;

std::vector<Frame> random_frames(bool fd, std::size_t length, std::size_t count) {
  std::mt19937 rng(1);
  std::vector<Frame> frames;
  std::vector<uint8_t> data(length);
  for (std::size_t i = 0; i < count; ++i) {
    for (auto& b : data) {
      b = static_cast<uint8_t>(rng());
    }
    FrameSpec spec;
    spec.id = rng() & kMaxStandardId;
    spec.fd = fd;
    spec.brs = fd;
    spec.data = data;
    frames.push_back(*Frame::create(spec));
  }
  return frames;
}

// Encodes `frames` (1024 of them) in turn.
void encode_frames(benchmark::State& state, const std::vector<Frame>& frames) {
  EncodedFrame out;
  std::size_t i = 0;
  for (auto _ : state) {
    encode(frames[i++ & 1023], out);
    benchmark::DoNotOptimize(out.length);
  }
  state.SetItemsProcessed(state.iterations());
  state.counters["frames_per_second"] =
      benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}

void BM_EncodeClassic8Bytes(benchmark::State& state) {
  encode_frames(state, random_frames(false, 8, 1024));
}
// Frames with many stuff bits, as a counter makes them: identifier and data the frame's number
// (little-endian), so that most data bytes are zero (about eleven stuff bits a frame, against
// three or so in a random one); bench/python's frames are these.
void BM_EncodeClassicCounter(benchmark::State& state) {
  std::vector<Frame> frames;
  for (uint64_t i = 0; i < 1024; ++i) {
    uint8_t data[8];
    for (std::size_t k = 0; k < 8; ++k) {
      data[k] = static_cast<uint8_t>(i >> (8 * k));
    }
    frames.push_back(*Frame::classic(static_cast<uint32_t>(i & kMaxStandardId), data));
  }
  encode_frames(state, frames);
}
void BM_EncodeFd64BytesBrs(benchmark::State& state) {
  encode_frames(state, random_frames(true, 64, 1024));
}

void BM_EncodeAndTimeClassic8Bytes(benchmark::State& state) {
  const auto frames = random_frames(false, 8, 1024);
  const BitTiming t = *sja1000::decode_btr(0x00, 0x14);
  EncodedFrame out;
  std::size_t i = 0;
  for (auto _ : state) {
    encode(frames[i++ & 1023], out);
    benchmark::DoNotOptimize(frame_duration(out, t));
  }
  state.SetItemsProcessed(state.iterations());
  state.counters["frames_per_second"] =
      benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}

BENCHMARK(BM_EncodeClassic8Bytes);
BENCHMARK(BM_EncodeClassicCounter);
BENCHMARK(BM_EncodeFd64BytesBrs);
BENCHMARK(BM_EncodeAndTimeClassic8Bytes);

}  // namespace
