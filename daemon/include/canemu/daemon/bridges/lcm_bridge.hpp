// An LCM bridge ([[bridge]] kind = "lcm", `canemu bridge add BUS --lcm`): an emulated bus and
// LCM (Lightweight Communications and Marshalling) channels joined through a node of its own
// (bridge.hpp). docs/bridges.md.
//
// Channels, all starting with the bridge's prefix (default CANEMU_<BUS>_):
//   <prefix>FRAMES  canemu_lcm.frame_t: every frame of the bus at the end of its EOF, those the
//                   bridge's node sent for TX included (from_tx)
//   <prefix>ERRORS  canemu_lcm.error_t: the bridge node's bus errors
//   <prefix>STATES  canemu_lcm.state_t: its error state changes and restarts after bus-off
//   <prefix>TX      canemu_lcm.frame_t from programs: queued and sent by the bridge's node;
//                   anything else arriving there is counted as rejected
//
// The LCM instance's descriptor (lcm_get_fileno) wakes canemud's loop like a SocketCAN bridge's
// socket; the bridge handles what arrived with lcm_handle_timeout(0), so the loop never waits.
// Publishing never waits either: UDP multicast drops rather than blocks.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <string_view>

#include <tl/expected.hpp>

#include "canemu/daemon/base/error.hpp"
#include "canemu/daemon/bridges/bridge.hpp"
#include "canemu/daemon/config/names.hpp"

struct _lcm_t;  // NOLINT(bugprone-reserved-identifier): LCM's own name of lcm_t, for tests

namespace canemu::daemon {

// canemud was built with LCM.
bool lcm_available();

// The LCM transport of bus `bus` on `url`, subscribed to <prefix>TX; the error says why not
// (built without LCM, a URL LCM cannot open).
Result<std::unique_ptr<BridgeTransport>> open_lcm(const std::string& bus, const std::string& url,
                                                  const std::string& prefix);

// The LCM instance of an LCM transport (nullptr for another transport): tests with the memq://
// provider publish and subscribe on it.
_lcm_t* lcm_instance(BridgeTransport& transport);

}  // namespace canemu::daemon
