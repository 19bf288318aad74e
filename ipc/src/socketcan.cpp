#include "canemu/ipc/socketcan.hpp"

#include <algorithm>
#include <cstdio>
#include <cstring>

namespace canemu::ipc::socketcan {

namespace {

// The CAN FD payload lengths of DLC 0..15 (ISO 11898-1; can_fd_dlc2len in the kernel).
constexpr uint8_t kFdLength[16] = {0, 1, 2, 3, 4, 5, 6, 7, 8, 12, 16, 20, 24, 32, 48, 64};

// ChannelMessage.error_type and .error_role and .state carry the model's CanErrorType
// (bit, stuff, form, crc, ack), ErrorRole (transmitter, receiver) and WireErrorState.
enum : uint8_t { kTypeBit = 0, kTypeStuff = 1, kTypeForm = 2, kTypeCrc = 3, kTypeAck = 4 };
enum : uint8_t { kRoleTransmitter = 0 };
enum : uint8_t { kStateActive = 0, kStateWarning = 1, kStatePassive = 2, kStateBusOff = 3 };

uint8_t counter(uint16_t value) {
  return static_cast<uint8_t>(std::min<uint16_t>(value, 255));
}

Frame error_frame(uint32_t classes, const ChannelMessage& m) {
  Frame f;
  f.can_id = kErrFlag | classes | kErrCnt;
  f.len = 8;
  f.data[6] = counter(m.tec);
  f.data[7] = counter(m.rec);
  return f;
}

constexpr char kHex[] = "0123456789ABCDEF";

}  // namespace

Frame restarted_frame() {
  Frame f;
  f.can_id = kErrFlag | kErrRestarted;
  f.len = 8;
  return f;
}

std::optional<Frame> from_message(const ChannelMessage& m) {
  switch (static_cast<ChannelMessageKind>(m.kind)) {
    case ChannelMessageKind::frame:
      break;
    case ChannelMessageKind::bus_error: {
      Frame f = error_frame(kErrProt | kErrBusError | (m.error_type == kTypeAck ? kErrAck : 0), m);
      f.data[2] = m.error_type == kTypeBit     ? kProtBit
                  : m.error_type == kTypeForm  ? kProtForm
                  : m.error_type == kTypeStuff ? kProtStuff
                                               : 0;
      if (m.error_role == kRoleTransmitter) {
        f.data[2] |= kProtTx;
      }
      f.data[3] = m.error_location;
      return f;
    }
    case ChannelMessageKind::state: {
      if (m.state == kStateBusOff) {
        return error_frame(kErrBusOff, m);
      }
      Frame f = error_frame(kErrCrtl, m);
      const bool tx = m.tec >= m.rec;
      f.data[1] = m.state == kStateWarning   ? (tx ? kCrtlTxWarning : kCrtlRxWarning)
                  : m.state == kStatePassive ? (tx ? kCrtlTxPassive : kCrtlRxPassive)
                                             : kCrtlActive;
      return f;
    }
    default:
      return std::nullopt;
  }
  Frame f;
  const bool extended = (m.flags & kMsgExtended) != 0;
  f.can_id = extended ? (m.id & kEffMask) | kEffFlag : m.id & kSffMask;
  f.fd = (m.flags & kMsgFd) != 0;
  const uint8_t dlc = m.dlc & 0x0F;
  if (f.fd) {
    f.len = kFdLength[dlc];
    f.flags = kFdFdf | ((m.flags & kMsgBrs) ? kFdBrs : 0) | ((m.flags & kMsgEsi) ? kFdEsi : 0);
  } else {
    f.len = std::min<uint8_t>(dlc, 8);
    f.len8_dlc = dlc > 8 ? dlc : 0;
  }
  if (m.flags & kMsgRemote) {
    f.can_id |= kRtrFlag;
  } else {
    std::memcpy(f.data, m.data, f.len);
  }
  return f;
}

std::optional<ChannelMessage> to_message(const Frame& f, std::string& error) {
  if (f.can_id & kErrFlag) {
    error = "an error frame cannot be sent onto a bus";
    return std::nullopt;
  }
  ChannelMessage m;
  m.kind = static_cast<uint8_t>(ChannelMessageKind::frame);
  const bool extended = (f.can_id & kEffFlag) != 0;
  m.id = f.can_id & (extended ? kEffMask : kSffMask);
  m.flags = extended ? kMsgExtended : 0;
  if (f.fd) {
    if (f.can_id & kRtrFlag) {
      error = "CAN FD has no remote frames";
      return std::nullopt;
    }
    if (f.len > 64) {
      error = "CAN FD length " + std::to_string(f.len) + " is above 64";
      return std::nullopt;
    }
    // A length between two DLCs' lengths takes the next DLC, as the kernel's CAN FD drivers
    // send it (canfd_sanitize_len()): the bytes up to that length are zero.
    const auto* at = std::lower_bound(std::begin(kFdLength), std::end(kFdLength), f.len);
    m.dlc = static_cast<uint8_t>(at - std::begin(kFdLength));
    m.flags |= kMsgFd | ((f.flags & kFdBrs) ? kMsgBrs : 0) | ((f.flags & kFdEsi) ? kMsgEsi : 0);
  } else {
    if (f.len > 8) {
      error = "classic CAN length " + std::to_string(f.len) + " is above 8";
      return std::nullopt;
    }
    m.dlc = f.len == 8 && f.len8_dlc > 8 && f.len8_dlc <= 15 ? f.len8_dlc : f.len;
  }
  if (f.can_id & kRtrFlag) {
    m.flags |= kMsgRemote;
  } else {
    std::memcpy(m.data, f.data, f.len);
  }
  return m;
}

std::vector<uint8_t> to_struct(const Frame& f) {
  std::vector<uint8_t> out(f.mtu(), 0);
  std::memcpy(out.data(), &f.can_id, 4);
  out[4] = f.len;
  out[5] = f.fd ? f.flags : 0;
  out[7] = f.fd ? 0 : f.len8_dlc;
  std::memcpy(out.data() + 8, f.data, f.fd ? 64 : 8);
  return out;
}

std::optional<Frame> from_struct(const uint8_t* bytes, std::size_t size) {
  if (size != kCanMtu && size != kCanFdMtu) {
    return std::nullopt;
  }
  Frame f;
  f.fd = size == kCanFdMtu;
  std::memcpy(&f.can_id, bytes, 4);
  f.len = std::min<uint8_t>(bytes[4], f.fd ? 64 : 8);
  if (f.fd) {
    f.flags = static_cast<uint8_t>(bytes[5] | kFdFdf);
  } else {
    f.len8_dlc = bytes[7];
  }
  std::memcpy(f.data, bytes + 8, size - 8);
  return f;
}

std::string candump_id(uint32_t can_id) {
  char id[16];
  if (can_id & (kErrFlag | kEffFlag)) {
    std::snprintf(id, sizeof id, "%08X", can_id & (kEffMask | kErrFlag));
  } else {
    std::snprintf(id, sizeof id, "%03X", can_id & kSffMask);
  }
  return id;
}

std::string candump_data(const Frame& f) {
  std::string text;
  text.reserve(2u * f.len);
  for (std::size_t i = 0; i < f.len; ++i) {
    text += kHex[f.data[i] >> 4];
    text += kHex[f.data[i] & 0x0F];
  }
  return text;
}

std::string candump_text(const Frame& f) {
  std::string text = candump_id(f.can_id);
  const bool dlc_suffix = !f.fd && f.len == 8 && f.len8_dlc > 8 && f.len8_dlc <= 15;
  if (!f.fd && (f.can_id & kRtrFlag) && !(f.can_id & kErrFlag)) {
    text += "#R";
    if (f.len > 0) {
      text += kHex[f.len & 0x0F];
    }
    if (dlc_suffix) {
      text += '_';
      text += kHex[f.len8_dlc];
    }
    return text;
  }
  if (f.fd) {
    text += "##";
    text += kHex[f.flags & (kFdBrs | kFdEsi)];
  } else {
    text += '#';
  }
  text += candump_data(f);
  if (dlc_suffix) {
    text += '_';
    text += kHex[f.len8_dlc];
  }
  return text;
}

std::string candump_line(int64_t ns, std::string_view bus, const Frame& f) {
  ns = std::max<int64_t>(ns, 0);
  char stamp[40];
  std::snprintf(stamp, sizeof stamp, "(%010lld.%06lld) ",
                static_cast<long long>(ns / 1'000'000'000),
                static_cast<long long>((ns % 1'000'000'000) / 1000));
  std::string line = stamp;
  line += bus;
  line += ' ';
  line += candump_text(f);
  return line;
}

std::vector<uint8_t> pcap_file_header() {
  return pcap::file_header(kCanFdMtu, kLinktypeCanSocketcan);
}

void append_pcap_record(std::vector<uint8_t>& out, int64_t ns, const Frame& f) {
  pcap::append_record_header(out, ns, static_cast<uint32_t>(f.mtu()));
  for (int i = 3; i >= 0; --i) {
    out.push_back(static_cast<uint8_t>(f.can_id >> (8 * i)));
  }
  out.push_back(f.len);
  out.push_back(f.fd ? static_cast<uint8_t>(f.flags | kFdFdf) : 0);
  out.push_back(0);
  out.push_back(f.fd ? 0 : f.len8_dlc);
  out.insert(out.end(), f.data, f.data + (f.fd ? 64 : 8));
}

}  // namespace canemu::ipc::socketcan
