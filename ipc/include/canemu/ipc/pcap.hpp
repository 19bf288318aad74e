// The pcap file format's own parts (the file header and each record's header, little-endian,
// nanosecond time stamps), shared by the SocketCAN captures (socketcan.hpp, LINKTYPE_CAN_SOCKETCAN)
// and the LIN captures (lin_pcap.hpp, LINKTYPE_LIN).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace canemu::ipc::pcap {

inline constexpr uint32_t kMagicNanoseconds = 0xA1B23C4D;
inline constexpr std::size_t kFileHeaderSize = 24;
inline constexpr std::size_t kRecordHeaderSize = 16;

void put_le16(std::vector<uint8_t>& out, uint16_t v);
void put_le32(std::vector<uint8_t>& out, uint32_t v);

// Version 2.4, time zone 0, `snaplen` and `linktype`.
std::vector<uint8_t> file_header(uint32_t snaplen, uint32_t linktype);
// Seconds and nanoseconds of `ns` (clamped at 0), then `size` as captured and original length.
void append_record_header(std::vector<uint8_t>& out, int64_t ns, uint32_t size);

}  // namespace canemu::ipc::pcap
