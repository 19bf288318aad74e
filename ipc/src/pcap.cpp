#include "canemu/ipc/pcap.hpp"

#include <algorithm>

namespace canemu::ipc::pcap {

void put_le16(std::vector<uint8_t>& out, uint16_t v) {
  out.push_back(static_cast<uint8_t>(v));
  out.push_back(static_cast<uint8_t>(v >> 8));
}

void put_le32(std::vector<uint8_t>& out, uint32_t v) {
  for (int i = 0; i < 4; ++i) {
    out.push_back(static_cast<uint8_t>(v >> (8 * i)));
  }
}

std::vector<uint8_t> file_header(uint32_t snaplen, uint32_t linktype) {
  std::vector<uint8_t> out;
  out.reserve(kFileHeaderSize);
  put_le32(out, kMagicNanoseconds);
  put_le16(out, 2);  // version 2.4
  put_le16(out, 4);
  put_le32(out, 0);  // thiszone
  put_le32(out, 0);  // sigfigs
  put_le32(out, snaplen);
  put_le32(out, linktype);
  return out;
}

void append_record_header(std::vector<uint8_t>& out, int64_t ns, uint32_t size) {
  ns = std::max<int64_t>(ns, 0);
  put_le32(out, static_cast<uint32_t>(ns / 1'000'000'000));
  put_le32(out, static_cast<uint32_t>(ns % 1'000'000'000));
  put_le32(out, size);
  put_le32(out, size);
}

}  // namespace canemu::ipc::pcap
