// The SocketCAN forms of a channel message, in one place for canemud (recorder, bridge) and the
// canemu tool (dump, send, gen): the kernel's struct can_frame / canfd_frame (linux/can.h), error
// frames as linux/can/error.h defines them, the candump log format that can-utils reads and
// writes (`(1700000000.000124) can0 123#1122`), and pcap captures with LINKTYPE_CAN_SOCKETCAN.
//
// Worked example (the same bytes are a test): a classic frame 0x123 with data 11 22 at simulated
// time 1.000000500 s is
//   candump:  `(0000000001.000000) can0 123#1122`
//   pcap record: 01 00 00 00  F4 01 00 00  10 00 00 00  10 00 00 00   (1 s, 500 ns, 16, 16)
//                00 00 01 23  02 00 00 00  11 22 00 00 00 00 00 00   (ID big-endian, len 2)
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "canemu/ipc/channel_message.hpp"
#include "canemu/ipc/pcap.hpp"

namespace canemu::ipc::socketcan {

// linux/can.h
inline constexpr uint32_t kEffFlag = 0x80000000;
inline constexpr uint32_t kRtrFlag = 0x40000000;
inline constexpr uint32_t kErrFlag = 0x20000000;
inline constexpr uint32_t kSffMask = 0x000007FF;
inline constexpr uint32_t kEffMask = 0x1FFFFFFF;
inline constexpr std::size_t kCanMtu = 16;
inline constexpr std::size_t kCanFdMtu = 72;
inline constexpr uint8_t kFdBrs = 0x01;
inline constexpr uint8_t kFdEsi = 0x02;
inline constexpr uint8_t kFdFdf = 0x04;

// linux/can/error.h: error classes in can_id, details in data[]
inline constexpr uint32_t kErrCrtl = 0x004;
inline constexpr uint32_t kErrProt = 0x008;
inline constexpr uint32_t kErrAck = 0x020;
inline constexpr uint32_t kErrBusOff = 0x040;
inline constexpr uint32_t kErrBusError = 0x080;
inline constexpr uint32_t kErrRestarted = 0x100;
inline constexpr uint32_t kErrCnt = 0x200;
inline constexpr uint8_t kCrtlRxWarning = 0x04;
inline constexpr uint8_t kCrtlTxWarning = 0x08;
inline constexpr uint8_t kCrtlRxPassive = 0x10;
inline constexpr uint8_t kCrtlTxPassive = 0x20;
inline constexpr uint8_t kCrtlActive = 0x40;
inline constexpr uint8_t kProtBit = 0x01;
inline constexpr uint8_t kProtForm = 0x02;
inline constexpr uint8_t kProtStuff = 0x04;
inline constexpr uint8_t kProtTx = 0x80;

// pcap: https://www.tcpdump.org/linktypes/LINKTYPE_CAN_SOCKETCAN.html
inline constexpr uint32_t kLinktypeCanSocketcan = 227;
inline constexpr uint32_t kPcapMagicNanoseconds = pcap::kMagicNanoseconds;
inline constexpr std::size_t kPcapFileHeaderSize = pcap::kFileHeaderSize;
inline constexpr std::size_t kPcapRecordHeaderSize = pcap::kRecordHeaderSize;

// A frame as the kernel's structs hold it: can_id with its EFF/RTR/ERR flags, the payload length
// (0..8 classic, 0..64 FD; for RTR the requested length), canfd_frame.flags (FD: BRS, ESI, FDF)
// and can_frame.len8_dlc (classic: the DLC 9..15 of an 8-byte frame, else 0).
struct Frame {
  uint32_t can_id = 0;
  uint8_t len = 0;
  uint8_t flags = 0;
  uint8_t len8_dlc = 0;
  bool fd = false;
  uint8_t data[64] = {};

  // CAN_MTU or CANFD_MTU: the bytes a CAN_RAW socket reads or writes for this frame.
  std::size_t mtu() const { return fd ? kCanFdMtu : kCanMtu; }
  bool operator==(const Frame&) const = default;
};

// The SocketCAN frame of a message from a channel's receive ring: a frame as it is; a bus error
// as CAN_ERR_PROT | CAN_ERR_BUSERROR | CAN_ERR_CNT (CAN_ERR_ACK too for an ACK error) with
// data[2] the type (BIT, FORM, STUFF, | TX when transmitting; 0 for CRC and ACK errors), data[3]
// the location (CAN_ERR_PROT_LOC_*); a state change as CAN_ERR_CRTL (data[1]: warning or passive,
// TX or RX by the larger counter, or ACTIVE) or CAN_ERR_BUSOFF, with CAN_ERR_CNT. Error frames
// carry TEC and REC in data[6] and data[7] (at most 255) and have len 8. Nothing for transmit
// confirmations and drops, which a SocketCAN interface does not show.
std::optional<Frame> from_message(const ChannelMessage& m);

// What a kernel CAN driver sends when it restarts a controller after bus-off (can_restart()):
// CAN_ERR_RESTARTED, len 8, data all 0.
Frame restarted_frame();

// The channel message of a frame read from a CAN_RAW socket (kind frame): identifier, flags and
// DLC from can_id, len, flags and len8_dlc. A CAN FD length between two DLCs' lengths (13) takes
// the next DLC (10: 16 bytes, the rest zero), as the kernel's CAN FD drivers send it
// (canfd_sanitize_len()). Error frames, FD remote frames and lengths above 8 (classic) or 64
// (FD) give nothing and `error` says why; identifiers are checked by whoever sends the message.
std::optional<ChannelMessage> to_message(const Frame& f, std::string& error);

// The struct can_frame (16 bytes) or canfd_frame (72 bytes) in host byte order, as write() on a
// CAN_RAW socket takes it; and back from what read() gave (16 or 72 bytes), nothing otherwise.
std::vector<uint8_t> to_struct(const Frame& f);
std::optional<Frame> from_struct(const uint8_t* bytes, std::size_t size);

// candump's frame text: `123#1122`, `12345678#R`, `123#R4`, `123##1AABB` (flags nibble: 1 BRS,
// 2 ESI), `123#1122334455667788_E` (classic DLC above 8), error frames with 8 hex digits
// `20000288#0000810200000800`.
std::string candump_text(const Frame& f);
// Two of its parts: the identifier (3 hex digits; 8 for a 29-bit one, CAN_EFF_FLAG not written,
// and for an error frame, CAN_ERR_FLAG written) and the data bytes as upper-case hex pairs.
std::string candump_id(uint32_t can_id);
std::string candump_data(const Frame& f);
// One line of a candump -L log: `(seconds.microseconds) bus frame`, seconds with 10 digits.
// `ns` is the time stamp in nanoseconds (negative ones print as 0).
std::string candump_line(int64_t ns, std::string_view bus, const Frame& f);

// A pcap file: the file header (nanosecond time stamps, snaplen 72, LINKTYPE_CAN_SOCKETCAN,
// little-endian like the files libpcap writes on x86) and one record per frame: the 16-byte
// record header, then the 16- or 72-byte frame with can_id in network byte order and FDF set on
// FD frames.
std::vector<uint8_t> pcap_file_header();
void append_pcap_record(std::vector<uint8_t>& out, int64_t ns, const Frame& f);

}  // namespace canemu::ipc::socketcan
