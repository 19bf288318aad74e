// Who may use canemud's control socket ([security] in the configuration): root, the daemon's
// own user, the listed users, and members of the listed groups. Names are resolved when the
// configuration is loaded (at start and on reload), never per connection; a peer's groups come
// from the kernel (SO_PEERGROUPS), so accepting a client reads no user database.
#pragma once

#include <cstdint>
#include <vector>

#include "canemu/daemon/config.hpp"

namespace canemu::daemon {

class AccessPolicy {
 public:
  // Replaces the lists with `security`'s; a user or group that does not exist is logged (a
  // warning) and left out.
  void resolve(const SecurityConfig& security);
  // Whether the peer on the connected AF_UNIX socket `fd`, whose uid is `uid`, may connect.
  bool allowed(int fd, uint32_t uid) const;

  const std::vector<uint32_t>& uids() const { return uids_; }
  const std::vector<uint32_t>& gids() const { return gids_; }

 private:
  std::vector<uint32_t> uids_;
  std::vector<uint32_t> gids_;
};

}  // namespace canemu::daemon
