// The bus engine against its recorded trace (engine_trace.hpp; docs/bus-engine.md, "Speed"):
// 100,000 random frames through the wire encoder and 1,000 random bus scenarios through CanBus
// must show exactly what they showed when tests/data/engine_trace/ was recorded.
//
// Environment (tests/README.md):
//   CANEMU_ENGINE_TRACE_RECORD=DIR  write frames.txt / scenarios.txt into DIR instead of
//                                   comparing (re-recording: only for an intended change)
//   CANEMU_ENGINE_TRACE_DUMP=frames:K or scenario:K
//                                   write that item's full trace to engine_trace_<kind>_<K>.txt
//                                   in the current directory (to diff two builds)
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "engine_trace.hpp"

namespace canemu::model::testing::engine_trace {
namespace {

// Under the sanitizers (`make asan`: a Debug build, about ten times slower) every fifth item is
// run and compared: the regular build compares them all, and the point of the sanitizer run is
// its memory and undefined-behaviour checks, which a fifth of the items exercise as well.
#if defined(__SANITIZE_ADDRESS__)
constexpr std::size_t kStride = 5;
#else
constexpr std::size_t kStride = 1;
#endif

const char* env(const char* name) {
  const char* v = std::getenv(name);
  return v != nullptr && *v != '\0' ? v : nullptr;
}

// What a record file holds: its header's values by key, its counts, and its items' hashes.
struct Record {
  std::map<std::string, std::string> header;
  std::map<std::string, uint64_t> counts;
  std::vector<std::vector<uint64_t>> items;  // item k: its hashes
  std::string error;
};

Record read_record(const std::string& path, const std::string& item_key) {
  Record r;
  std::ifstream in(path);
  if (!in) {
    r.error = "cannot read " + path;
    return r;
  }
  std::string line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    if (line.empty() || line[0] == '#') {
      continue;
    }
    std::istringstream words(line);
    std::string key;
    words >> key;
    if (key == "count") {
      std::string name;
      uint64_t value = 0;
      words >> name >> value;
      r.counts[name] = value;
    } else if (key == item_key) {
      std::size_t k = 0;
      words >> k;
      if (k != r.items.size()) {
        r.error = path + ":" + std::to_string(number) + ": " + item_key + " " + std::to_string(k) +
                  " where " + std::to_string(r.items.size()) + " was expected";
        return r;
      }
      std::vector<uint64_t>& hashes = r.items.emplace_back();
      std::string h;
      while (words >> h) {
        hashes.push_back(std::stoull(h, nullptr, 16));
      }
    } else {
      std::string value;
      std::getline(words >> std::ws, value);
      r.header[key] = value;
    }
    if (words.fail() && !words.eof()) {
      r.error = path + ":" + std::to_string(number) + ": cannot read \"" + line + "\"";
      return r;
    }
  }
  return r;
}

std::string hex(uint64_t v) {
  char buf[17];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(v));
  return buf;
}

std::string seed_text(uint64_t seed) {
  return "0x" + hex(seed);
}

// The item CANEMU_ENGINE_TRACE_DUMP asks for, if it is of `kind`.
std::optional<std::size_t> dump_request(const std::string& kind) {
  const char* v = env("CANEMU_ENGINE_TRACE_DUMP");
  if (v == nullptr) {
    return std::nullopt;
  }
  const std::string s(v);
  const std::string prefix = kind + ":";
  if (s.rfind(prefix, 0) != 0) {
    return std::nullopt;
  }
  return static_cast<std::size_t>(std::stoull(s.substr(prefix.size())));
}

// Writes an item's trace into the current directory; returns where.
std::string write_item(const std::string& kind, std::size_t k, const std::string& text) {
  const std::filesystem::path path =
      std::filesystem::absolute("engine_trace_" + kind + "_" + std::to_string(k) + ".txt");
  std::ofstream(path) << text;
  return path.string();
}

const std::string kHeaderComment =
    "# Recorded from the CAN bus engine by tests/firmware_model/bus/engine_trace_test.cpp\n"
    "# (docs/bus-engine.md, \"Speed\"; tests/README.md says how and when to re-record).\n";

std::string record_dir_or_default() {
  const char* dir = env("CANEMU_ENGINE_TRACE_RECORD");
  return dir != nullptr ? dir : CANEMU_ENGINE_TRACE_DIR;
}

// The hashes of every frame chunk: the trace within EncodedFrame's contract, then the raw one.
struct FrameRun {
  std::vector<std::pair<uint64_t, uint64_t>> hashes;
  FrameCounts counts;
};

FrameRun run_frames() {
  FrameRun run;
  std::string text;
  std::string raw;
  run.hashes.resize(kChunks);
  for (std::size_t k = 0; k < kChunks; k += kStride) {
    text.clear();
    raw.clear();
    trace_frame_chunk(k, text, raw, run.counts);
    run.hashes[k] = {fnv1a(text), fnv1a(raw)};
  }
  return run;
}

struct ScenarioRun {
  std::vector<uint64_t> hashes;
  ScenarioCounts counts;
};

ScenarioRun run_scenarios() {
  ScenarioRun run;
  std::string text;
  run.hashes.resize(kScenarios);
  for (std::size_t k = 0; k < kScenarios; k += kStride) {
    text.clear();
    run_scenario(k, text, run.counts);
    run.hashes[k] = fnv1a(text);
  }
  return run;
}

template <class CountsT>
void append_counts(std::string& out, const CountsT& counts) {
  for (std::size_t i = 0; i < CountsT::size(); ++i) {
    out += "count " + std::string(CountsT::name(i)) + " " + std::to_string(counts[i]) + "\n";
  }
}

// The run's counts are the record's (when every item ran), and each is above zero (so the trace
// covers what it says).
template <class CountsT>
void expect_counts(const CountsT& counts, const Record& record) {
  EXPECT_EQ(record.counts.size(), CountsT::size());
  for (std::size_t i = 0; i < CountsT::size(); ++i) {
    const std::string name(CountsT::name(i));
    const auto it = record.counts.find(name);
    if (it == record.counts.end()) {
      ADD_FAILURE() << "the record has no count " << name;
      continue;
    }
    if (kStride == 1) {
      EXPECT_EQ(counts[i], it->second) << name;
    }
    EXPECT_GT(counts[i], 0u) << name << ": the trace does not exercise this";
  }
}

TEST(EngineTrace, HundredThousandRandomFramesEncodeAsRecorded) {
  if (const auto k = dump_request("frames")) {
    ASSERT_LT(*k, kChunks);
    std::string text;
    std::string raw;
    FrameCounts counts;
    trace_frame_chunk(*k, text, raw, counts);
    std::cout << "chunk " << *k << ": " << write_item("frames", *k, text + "raw\n" + raw) << "\n";
  }
  const FrameRun run = run_frames();
  if (env("CANEMU_ENGINE_TRACE_RECORD") != nullptr) {
    ASSERT_EQ(kStride, 1u) << "record from a build without the sanitizers";
    std::string out = kHeaderComment;
    out +=
        "# chunk K: FNV-1a 64 of the trace of frames K*1000..K*1000+999 within EncodedFrame's\n"
        "# contract, then of what the encoder leaves beyond it (raw).\n";
    out += "generator " + std::to_string(kGeneratorVersion) + "\nseed " + seed_text(kFrameSeed) +
           "\nframes " + std::to_string(kFrames) + "\nper-chunk " +
           std::to_string(kFramesPerChunk) + "\n";
    append_counts(out, run.counts);
    for (std::size_t k = 0; k < run.hashes.size(); ++k) {
      out += "chunk " + std::to_string(k) + " " + hex(run.hashes[k].first) + " " +
             hex(run.hashes[k].second) + "\n";
    }
    const std::string path = record_dir_or_default() + "/frames.txt";
    std::ofstream(path) << out;
    std::cout << "recorded " << path << "\n";
    return;
  }
  const Record record = read_record(std::string(CANEMU_ENGINE_TRACE_DIR) + "/frames.txt", "chunk");
  ASSERT_EQ(record.error, "");
  ASSERT_EQ(record.header.at("generator"), std::to_string(kGeneratorVersion))
      << "the generators changed: re-record (tests/README.md)";
  ASSERT_EQ(record.header.at("seed"), seed_text(kFrameSeed));
  ASSERT_EQ(record.header.at("frames"), std::to_string(kFrames));
  ASSERT_EQ(record.items.size(), kChunks);
  expect_counts(run.counts, record);
  for (std::size_t k = 0; k < kChunks; k += kStride) {
    ASSERT_EQ(record.items[k].size(), 2u) << "chunk " << k;
    const bool text_same = run.hashes[k].first == record.items[k][0];
    const bool raw_same = run.hashes[k].second == record.items[k][1];
    if (text_same && raw_same) {
      continue;
    }
    std::string text;
    std::string raw;
    FrameCounts counts;
    trace_frame_chunk(k, text, raw, counts);
    const std::string path = write_item("frames", k, text + "raw\n" + raw);
    if (!text_same) {
      ADD_FAILURE() << "frame chunk " << k << " (frames " << k * kFramesPerChunk << ".."
                    << (k + 1) * kFramesPerChunk - 1 << ", seed "
                    << seed_text(item_seed(kFrameSeed, k))
                    << ") encodes otherwise than recorded: " << hex(run.hashes[k].first)
                    << " against " << hex(record.items[k][0]) << ". Its trace now (also in " << path
                    << "; CANEMU_ENGINE_TRACE_DUMP=frames:" << k
                    << " writes it from another build):\n"
                    << text;
    } else {
      ADD_FAILURE() << "frame chunk " << k << " (seed " << seed_text(item_seed(kFrameSeed, k))
                    << "): every bit within the frames is as recorded, but the encoder leaves "
                       "other words or fields beyond them (outside EncodedFrame's contract; "
                       "if intended, re-record and say so). Now (also in "
                    << path << "):\n"
                    << raw;
    }
    return;  // the first difference only
  }
}

TEST(EngineTrace, ThousandRandomBusScenariosRunAsRecorded) {
  if (const auto k = dump_request("scenario")) {
    ASSERT_LT(*k, kScenarios);
    std::string text;
    ScenarioCounts counts;
    run_scenario(*k, text, counts);
    std::cout << "scenario " << *k << ": " << write_item("scenario", *k, text) << "\n";
  }
  const ScenarioRun run = run_scenarios();
  if (env("CANEMU_ENGINE_TRACE_RECORD") != nullptr) {
    ASSERT_EQ(kStride, 1u) << "record from a build without the sanitizers";
    std::string out = kHeaderComment;
    out += "# scenario K: FNV-1a 64 of the trace of bus scenario K.\n";
    out += "generator " + std::to_string(kGeneratorVersion) + "\nseed " + seed_text(kScenarioSeed) +
           "\nscenarios " + std::to_string(kScenarios) + "\n";
    append_counts(out, run.counts);
    for (std::size_t k = 0; k < run.hashes.size(); ++k) {
      out += "scenario " + std::to_string(k) + " " + hex(run.hashes[k]) + "\n";
    }
    const std::string path = record_dir_or_default() + "/scenarios.txt";
    std::ofstream(path) << out;
    std::cout << "recorded " << path << "\n";
    return;
  }
  const Record record =
      read_record(std::string(CANEMU_ENGINE_TRACE_DIR) + "/scenarios.txt", "scenario");
  ASSERT_EQ(record.error, "");
  ASSERT_EQ(record.header.at("generator"), std::to_string(kGeneratorVersion))
      << "the generators changed: re-record (tests/README.md)";
  ASSERT_EQ(record.header.at("seed"), seed_text(kScenarioSeed));
  ASSERT_EQ(record.header.at("scenarios"), std::to_string(kScenarios));
  ASSERT_EQ(record.items.size(), kScenarios);
  for (std::size_t k = 0; k < kScenarios; k += kStride) {
    ASSERT_EQ(record.items[k].size(), 1u) << "scenario " << k;
    if (run.hashes[k] == record.items[k][0]) {
      continue;
    }
    std::string text;
    ScenarioCounts counts;
    run_scenario(k, text, counts);
    const std::string path = write_item("scenario", k, text);
    ADD_FAILURE() << "bus scenario " << k << " (seed " << seed_text(item_seed(kScenarioSeed, k))
                  << ") runs otherwise than recorded: " << hex(run.hashes[k]) << " against "
                  << hex(record.items[k][0]) << ". Its trace now (also in " << path
                  << "; CANEMU_ENGINE_TRACE_DUMP=scenario:" << k
                  << " writes it from another build):\n"
                  << text;
    break;  // the first difference only
  }
  // Checked after the hashes: a changed engine usually changes these too.
  expect_counts(run.counts, record);
}

// Each generator gives the same items again, and different ones for different items; and the
// record's counts (which the two tests above hold to the run) say that the trace covers every
// kind of frame and event it claims to.
TEST(EngineTrace, GeneratorsAreDeterministicAndTheRecordCoversWhatItClaims) {
  std::string a;
  std::string b;
  std::string raw;
  FrameCounts fc;
  trace_frame_chunk(7, a, raw, fc);
  trace_frame_chunk(7, b, raw, fc);
  EXPECT_EQ(a, b);
  b.clear();
  trace_frame_chunk(8, b, raw, fc);
  EXPECT_NE(a, b);

  ScenarioCounts sc;
  for (const std::size_t k : {0u, 1u, 2u}) {
    a.clear();
    b.clear();
    run_scenario(k, a, sc);
    run_scenario(k, b, sc);
    EXPECT_EQ(a, b) << "scenario " << k;
    EXPECT_NE(a.find("bus frame"), std::string::npos) << "scenario " << k << " sends nothing";
  }
  a.clear();
  b.clear();
  run_scenario(3, a, sc);
  run_scenario(4, b, sc);
  EXPECT_NE(a, b);

  const Record frames = read_record(std::string(CANEMU_ENGINE_TRACE_DIR) + "/frames.txt", "chunk");
  ASSERT_EQ(frames.error, "");
  EXPECT_EQ(frames.counts.size(), FrameCounts::size());
  for (const auto& [name, n] : frames.counts) {
    EXPECT_GT(n, 0u) << name;
  }
  EXPECT_EQ(frames.counts.at("frames"), kFrames);
  const Record scenarios =
      read_record(std::string(CANEMU_ENGINE_TRACE_DIR) + "/scenarios.txt", "scenario");
  ASSERT_EQ(scenarios.error, "");
  EXPECT_EQ(scenarios.counts.size(), ScenarioCounts::size());
  for (const auto& [name, n] : scenarios.counts) {
    EXPECT_GT(n, 0u) << name;
  }
}

}  // namespace
}  // namespace canemu::model::testing::engine_trace
