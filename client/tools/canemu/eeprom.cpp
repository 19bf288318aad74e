// canemu eeprom: an SL-CANi S-Link's EEPROM (64 words), shown and written word by word.
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <CLI/CLI.hpp>

#include "canemu/client/connection.hpp"
#include "command.hpp"

namespace canemu::cli {

namespace {

// "WORD=VALUE": decimal word, value in C notation (0x1F, 31).
bool parse_assignment(const std::string& text, uint16_t& word, uint16_t& value) {
  const auto eq = text.find('=');
  if (eq == std::string::npos) {
    return false;
  }
  try {
    std::size_t used = 0;
    const unsigned long w = std::stoul(text.substr(0, eq), &used, 10);
    if (used != eq || w > 63) {
      return false;
    }
    const std::string v = text.substr(eq + 1);
    const unsigned long x = std::stoul(v, &used, 0);
    if (used != v.size() || x > 0xFFFF) {
      return false;
    }
    word = static_cast<uint16_t>(w);
    value = static_cast<uint16_t>(x);
    return true;
  } catch (const std::exception&) {
    return false;
  }
}

int run_eeprom(const std::string& socket, int slot, const std::vector<std::string>& writes) {
  std::vector<std::pair<uint16_t, uint16_t>> words;
  for (const std::string& w : writes) {
    uint16_t word = 0;
    uint16_t value = 0;
    if (!parse_assignment(w, word, value)) {
      return fail(fmt::format("'{}' is not WORD=VALUE (word 0..63, value 0..0xFFFF)", w));
    }
    words.emplace_back(word, value);
  }
  auto c = connect(socket, "canemu eeprom");
  if (!c) {
    return fail(c.error().message);
  }
  auto request = [&](ipc::SlcanOp op, uint16_t word, uint16_t value) {
    auto m = ipc::make_message<ipc::SlcanRequest>();
    m.op = static_cast<uint16_t>(op);
    m.slot = static_cast<uint8_t>(slot);
    m.value = word;
    m.handle = value;
    return c->call<ipc::SlcanRequest, ipc::SlcanReply>(m);
  };
  for (const auto& [word, value] : words) {
    if (auto r = request(ipc::SlcanOp::eeprom_write, word, value); !r) {
      return fail(r.error().message);
    }
  }
  auto r = request(ipc::SlcanOp::eeprom_read, 0, 0);
  if (!r) {
    return fail(r.error().message);
  }
  for (unsigned row = 0; row < ipc::kSlcanEepromWords; row += 8) {
    std::string line = fmt::format("{:2}:", row);
    for (unsigned k = row; k < row + 8; ++k) {
      line += fmt::format(" {:04X}", r->eeprom[k]);
    }
    std::printf("%s\n", line.c_str());
  }
  return 0;
}

}  // namespace

Command add_eeprom(CLI::App& app, const std::string& socket) {
  auto* cmd = app.add_subcommand(
      "eeprom",
      "an SL-CANi S-Link's EEPROM: 'eeprom 1' shows it, 'eeprom 1 15=100 16=16' writes words "
      "(13..19 and 32..63) first");
  auto slot = std::make_shared<int>(0);
  auto writes = std::make_shared<std::vector<std::string>>();
  cmd->add_option("SLOT", *slot, "the S-Link's slot, 0..5")->required()->check(CLI::Range(0, 5));
  cmd->add_option("WORD=VALUE", *writes, "words to write, e.g. 15=100 or 40=0x1234");
  return {cmd, [&socket, slot, writes] { return run_eeprom(socket, *slot, *writes); }};
}

}  // namespace canemu::cli
