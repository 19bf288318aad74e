// Frames as text, the way can-utils writes them: cansend's syntax to read (`123#1122`,
// `12345678#R4`, `123##1AABB`) and candump's log format to write (`(0.000124) can0 123#1122`),
// with error and state messages as SocketCAN error frames (linux/can/error.h); the writing is
// ipc/socketcan.hpp's, shared with canemud's recorder and bridge.
#pragma once

#include <optional>
#include <string>
#include <string_view>

#include "canemu/firmware_model/bus/frame.hpp"
#include "canemu/ipc/channel_message.hpp"

namespace canemu::cli {

// A frame to send from cansend syntax: <id>#<data>, <id>#R[<len>], <id>##<flags><data>; 3 hex
// digits make an 11-bit identifier, 8 a 29-bit one; data as hex pairs, optionally separated by
// '.'; a classic frame's DLC above 8 as candump writes it, `_X` (9..F) after 8 data bytes or R8
// (123#1122334455667788_E, 123#R8_E). Nothing, with `error` set, when the text is not a valid
// frame.
std::optional<ipc::ChannelMessage> parse_cansend(std::string_view text, std::string& error);

// The frame text of a message as ipc/socketcan.hpp writes it: `123#1122`, `123#R4`,
// `123##1AABB`, or for bus errors and state changes a SocketCAN error frame; empty for transmit
// confirmations.
std::string candump_frame(const ipc::ChannelMessage& m);

// The wire model's frame of a message of kind `frame`: its identifier, flags, DLC and data
// checked as canemud checks a frame a channel sends (Frame::create); an error for anything else.
model::Result<model::Frame> to_frame(const ipc::ChannelMessage& m);

}  // namespace canemu::cli
