// A frame into the fields canemu's DDS types give it (canemu_dds.idl's Frame, canemu_net.idl's
// Request and Event: id, extended, remote, fd, brs, esi, dlc, len, data[64]), and back.
#pragma once

#include <algorithm>
#include <cstring>
#include <optional>
#include <span>

#include "canemu/firmware_model/bus/frame.hpp"

namespace canemu::daemon {

template <typename M>
void put_frame_fields(M& m, const model::Frame& f) {
  m.id = f.id();
  m.extended = f.extended();
  m.remote = f.remote();
  m.fd = f.fd();
  m.brs = f.brs();
  m.esi = f.esi();
  m.dlc = f.dlc();
  m.len = static_cast<uint8_t>(f.length());
  std::memcpy(m.data, f.data().data(), f.length());
}

// The frame the fields describe, validated as any frame; nothing if they describe none.
template <typename M>
std::optional<model::Frame> frame_of_fields(const M& m) {
  model::FrameSpec spec;
  spec.id = m.id;
  spec.extended = m.extended;
  spec.remote = m.remote;
  spec.fd = m.fd;
  spec.brs = m.brs;
  spec.esi = m.esi;
  spec.dlc = m.dlc;
  spec.data = std::span<const uint8_t>(m.data, m.remote ? 0 : std::min<std::size_t>(m.len, 64));
  auto f = model::Frame::create(spec);
  if (!f) {
    return std::nullopt;
  }
  return *f;
}

}  // namespace canemu::daemon
