// A LIN bus in a pcap capture: LINKTYPE_LIN (212), as
// https://www.tcpdump.org/linktypes/LINKTYPE_LIN.html defines it and Wireshark's LIN dissector
// reads it. canemud's [[recorder]] and `canemu record` / `canemu dump --format pcap` on a LIN
// bus write it through CaptureWriter (capture_writer.hpp).
//
// A record is an 8-byte header and the payload, padded to whole 32-bit words (12 bytes with up
// to 4 payload bytes, 16 with 5 to 8), as the format's word diagram and Wireshark have it:
//   0     message format revision: 1
//   1..3  reserved: 0
//   4     payload length (bits 7..4), message type (bits 3..2: 0 frame, 3 event), checksum type
//         (bits 1..0: 0 unknown or wrong, 1 classic, 2 enhanced)
//   5     protected identifier (identifier and its two parity bits)
//   6     checksum
//   7     error bits (kError*)
//   8..   payload: the frame's data bytes, or an event's 32-bit type, big-endian
// An event has its type only: checksum type, PID, checksum and errors are 0.
//
// Worked example (the same bytes are a test): frame 10h with data 01 00 and its enhanced
// checksum AE (PID 50h) at simulated time 0.003333333 s is
//   pcap record: 00 00 00 00  D5 DC 32 00  0C 00 00 00  0C 00 00 00   (0 s, 3333333 ns, 12, 12)
//                01 00 00 00  22 50 AE 00  01 00 00 00                (length 2, frame, enhanced)
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace canemu::ipc::lin_pcap {

inline constexpr uint32_t kLinktypeLin = 212;
inline constexpr uint8_t kFormatRevision = 1;
inline constexpr std::size_t kMaxRecordSize = 16;  // the snap length
inline constexpr uint8_t kMaxData = 8;

// The error bits.
inline constexpr uint8_t kErrorNoSlaveResponse = 0x01;  // nobody answered the header
inline constexpr uint8_t kErrorFraming = 0x02;          // a low-level reception error
inline constexpr uint8_t kErrorParity = 0x04;           // the PID's parity bits are wrong
inline constexpr uint8_t kErrorChecksum = 0x08;
inline constexpr uint8_t kErrorInvalidId = 0x10;  // a frame of identifier 3Eh or 3Fh
inline constexpr uint8_t kErrorOverflow = 0x20;   // messages were lost before this one

// The event types.
inline constexpr uint32_t kEventGoToSleep = 0xB0B00001;   // by the go-to-sleep command
inline constexpr uint32_t kEventInactivity = 0xB0B00002;  // go-to-sleep: 4 s without activity
inline constexpr uint32_t kEventWakeUp = 0xB0B00004;      // a wake-up pulse

enum class MessageType : uint8_t { frame = 0, event = 3 };
enum class ChecksumType : uint8_t { unknown = 0, classic = 1, enhanced = 2 };

struct Message {
  MessageType type = MessageType::frame;
  ChecksumType checksum_type = ChecksumType::unknown;
  uint8_t pid = 0;
  uint8_t checksum = 0;
  uint8_t errors = 0;
  uint8_t length = 0;  // data bytes, 0..8 (0: a header without a response)
  uint8_t data[kMaxData] = {};
  uint32_t event = 0;  // an event's type

  bool operator==(const Message&) const = default;
};

// An event record of type `type` (kEvent*).
Message event(uint32_t type);

// The record's bytes (12 or 16; a length above 8 is taken as 8).
std::vector<uint8_t> encode(const Message& m);

// A pcap file: the file header (nanosecond time stamps, snap length 16, LINKTYPE_LIN,
// little-endian like the CAN captures) and one record per message: the 16-byte record header
// stamped `ns` (negative ones as 0), then encode(m).
std::vector<uint8_t> pcap_file_header();
void append_pcap_record(std::vector<uint8_t>& out, int64_t ns, const Message& m);

}  // namespace canemu::ipc::lin_pcap
