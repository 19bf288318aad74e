#include "canemu/ipc/lin_pcap.hpp"

#include <algorithm>

#include "canemu/ipc/pcap.hpp"

namespace canemu::ipc::lin_pcap {

using pcap::put_le16;
using pcap::put_le32;

Message event(uint32_t type) {
  Message m;
  m.type = MessageType::event;
  m.event = type;
  return m;
}

std::vector<uint8_t> encode(const Message& m) {
  std::vector<uint8_t> out;
  out.reserve(kMaxRecordSize);
  out.push_back(kFormatRevision);
  out.insert(out.end(), 3, 0);
  const bool is_event = m.type == MessageType::event;
  const uint8_t length = is_event ? 4 : std::min(m.length, kMaxData);
  const auto type = static_cast<uint8_t>(m.type);
  const auto checksum_type = is_event ? 0 : static_cast<uint8_t>(m.checksum_type);
  out.push_back(
      static_cast<uint8_t>((length << 4) | ((type & 0x03) << 2) | (checksum_type & 0x03)));
  out.push_back(is_event ? 0 : m.pid);
  out.push_back(is_event ? 0 : m.checksum);
  out.push_back(is_event ? 0 : m.errors);
  if (is_event) {
    for (int i = 3; i >= 0; --i) {
      out.push_back(static_cast<uint8_t>(m.event >> (8 * i)));
    }
  } else {
    out.insert(out.end(), m.data, m.data + length);
  }
  out.resize(length <= 4 ? 12 : 16, 0);
  return out;
}

std::vector<uint8_t> pcap_file_header() {
  return pcap::file_header(kMaxRecordSize, kLinktypeLin);
}

void append_pcap_record(std::vector<uint8_t>& out, int64_t ns, const Message& m) {
  const std::vector<uint8_t> record = encode(m);
  pcap::append_record_header(out, ns, static_cast<uint32_t>(record.size()));
  out.insert(out.end(), record.begin(), record.end());
}

}  // namespace canemu::ipc::lin_pcap
