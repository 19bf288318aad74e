#include "frame_text.hpp"

#include <cctype>
#include <cstring>

#include <fmt/format.h>

#include "canemu/ipc/socketcan.hpp"

namespace canemu::cli {

namespace {

bool all_hex(std::string_view s) {
  for (char ch : s) {
    if (!std::isxdigit(static_cast<unsigned char>(ch))) {
      return false;
    }
  }
  return !s.empty();
}

int hex(char ch) {
  return std::isdigit(static_cast<unsigned char>(ch)) ? ch - '0' : std::tolower(ch) - 'a' + 10;
}

}  // namespace

std::optional<ipc::ChannelMessage> parse_cansend(std::string_view text, std::string& error) {
  const std::size_t hash = text.find('#');
  if (hash == std::string_view::npos || (hash != 3 && hash != 8) ||
      !all_hex(text.substr(0, hash))) {
    error = "expected <id>#<data> with a 3- or 8-digit hex identifier";
    return std::nullopt;
  }
  ipc::ChannelMessage m;
  for (char ch : text.substr(0, hash)) {
    m.id = (m.id << 4) | static_cast<uint32_t>(hex(ch));
  }
  if (hash == 8) {
    m.flags |= ipc::kMsgExtended;
  }
  std::string_view rest = text.substr(hash + 1);
  // candump's `_X` after 8 data bytes or R8 (can-utils' len8_dlc): a classic frame's DLC 9..F,
  // which still carries 8 bytes.
  std::optional<uint8_t> raw_dlc;
  if (const std::size_t underscore = rest.find('_'); underscore != std::string_view::npos) {
    const std::string_view suffix = rest.substr(underscore + 1);
    if (!rest.empty() && rest[0] == '#') {
      error = "a CAN FD frame takes no _DLC suffix (its length gives the DLC)";
      return std::nullopt;
    }
    if (suffix.size() != 1 || !std::isxdigit(static_cast<unsigned char>(suffix[0])) ||
        hex(suffix[0]) < 9) {
      error = fmt::format(
          "'_{}': a classic DLC above 8 is one hex digit 9..F after 8 data bytes or R8, as "
          "candump writes it (123#1122334455667788_E, 123#R8_E)",
          suffix);
      return std::nullopt;
    }
    raw_dlc = static_cast<uint8_t>(hex(suffix[0]));
    rest = rest.substr(0, underscore);
  }
  bool fd = false;
  if (!rest.empty() && rest[0] == '#') {
    if (rest.size() < 2 || !std::isxdigit(static_cast<unsigned char>(rest[1]))) {
      error = "CAN FD frames need a flags digit after ## (1 = BRS, 2 = ESI)";
      return std::nullopt;
    }
    fd = true;
    const int flags = hex(rest[1]);
    m.flags |= ipc::kMsgFd | ((flags & 1) ? ipc::kMsgBrs : 0) | ((flags & 2) ? ipc::kMsgEsi : 0);
    rest = rest.substr(2);
  } else if (!rest.empty() && (rest[0] == 'R' || rest[0] == 'r')) {
    m.flags |= ipc::kMsgRemote;
    rest = rest.substr(1);
    if (rest.size() > 1 || (rest.size() == 1 && (rest[0] < '0' || rest[0] > '8'))) {
      error = "a remote frame takes one length digit (0..8) after R";
      return std::nullopt;
    }
    m.dlc = rest.empty() ? 0 : static_cast<uint8_t>(rest[0] - '0');
    if (raw_dlc && m.dlc != 8) {
      error = fmt::format("'_{:X}' follows R8 only (a remote frame's DLC above 8)", *raw_dlc);
      return std::nullopt;
    }
    m.dlc = raw_dlc.value_or(m.dlc);
    rest = {};
  }
  std::size_t length = 0;
  for (std::size_t i = 0; i < rest.size();) {
    if (rest[i] == '.') {
      ++i;
      continue;
    }
    if (i + 1 >= rest.size() || !std::isxdigit(static_cast<unsigned char>(rest[i])) ||
        !std::isxdigit(static_cast<unsigned char>(rest[i + 1]))) {
      error = "data must be pairs of hex digits";
      return std::nullopt;
    }
    if (length == sizeof m.data) {
      error = "more than 64 data bytes";
      return std::nullopt;
    }
    m.data[length++] = static_cast<uint8_t>(hex(rest[i]) * 16 + hex(rest[i + 1]));
    i += 2;
  }
  if (!(m.flags & ipc::kMsgRemote)) {
    const auto dlc = model::length_to_dlc(length, fd);
    if (!dlc || (!fd && length > 8)) {
      error = fmt::format("{} data bytes is not a {} frame length", length,
                          fd ? "CAN FD" : "classic CAN");
      return std::nullopt;
    }
    m.dlc = *dlc;
    if (raw_dlc && length != 8) {
      error =
          fmt::format("'_{:X}' follows 8 data bytes only, not {} (a DLC above 8 still carries 8)",
                      *raw_dlc, length);
      return std::nullopt;
    }
    m.dlc = raw_dlc.value_or(m.dlc);
  }
  // Everything else (identifier range, flag combinations) as the daemon will check it.
  auto checked = to_frame(m);
  if (!checked) {
    error = checked.error().message;
    return std::nullopt;
  }
  return m;
}

model::Result<model::Frame> to_frame(const ipc::ChannelMessage& m) {
  if (m.kind != static_cast<uint8_t>(ipc::ChannelMessageKind::frame)) {
    return model::model_error(model::ModelErrc::invalid_flags,
                              fmt::format("message kind {} is not a frame", m.kind));
  }
  if (m.dlc > model::kMaxDlc) {
    return model::model_error(model::ModelErrc::invalid_dlc,
                              fmt::format("DLC {} is above 15", m.dlc));
  }
  model::FrameSpec spec;
  spec.id = m.id;
  spec.extended = (m.flags & ipc::kMsgExtended) != 0;
  spec.remote = (m.flags & ipc::kMsgRemote) != 0;
  spec.fd = (m.flags & ipc::kMsgFd) != 0;
  spec.brs = (m.flags & ipc::kMsgBrs) != 0;
  spec.esi = (m.flags & ipc::kMsgEsi) != 0;
  spec.dlc = m.dlc;
  spec.data =
      std::span<const uint8_t>(m.data, spec.remote ? 0 : model::dlc_to_length(m.dlc, spec.fd));
  return model::Frame::create(spec);
}

std::string candump_frame(const ipc::ChannelMessage& m) {
  const auto f = ipc::socketcan::from_message(m);
  return f ? ipc::socketcan::candump_text(*f) : std::string();
}

}  // namespace canemu::cli
