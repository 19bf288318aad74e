// Who may use canemud's control socket ([security] in the configuration): root, the daemon's
// own user, the listed users, and members of the listed groups (primary or supplementary). Names
// are resolved when the configuration is loaded (at start and on reload), never per connection;
// a peer's groups come from the kernel (SO_PEERCRED, SO_PEERGROUPS), so accepting a client reads
// no user database. The socket file's own mode and group are the first gate: the kernel refuses
// whoever may not write to it before canemud sees them.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <tl/expected.hpp>

#include "canemu/daemon/base/error.hpp"
#include "canemu/daemon/config/config.hpp"

namespace canemu::daemon {

class AccessPolicy {
 public:
  // Replaces the lists with `security`'s; a user or group that does not exist is logged (a
  // warning) and left out.
  void resolve(const SecurityConfig& security);
  // Whether the peer on the connected AF_UNIX socket `fd`, whose uid and primary gid are `uid`
  // and `gid`, may connect.
  bool allowed(int fd, uint32_t uid, uint32_t gid) const;
  // Whether that peer is an administrator: root, canemud's own user, or a member of
  // `admin_groups` (it may clear every fault scenario).
  bool admin(int fd, uint32_t uid, uint32_t gid) const;
  // The socket file canemud bound, as lstat saw it just after the bind.
  struct SocketFile {
    uint64_t dev = 0;
    uint64_t ino = 0;
  };
  // Identifies the socket file at `path` (not following a link); an error names the problem.
  static Result<SocketFile> socket_file(const std::string& path);
  // Gives the socket file at `path` the configured mode and group, if it is still the file
  // `bound` (a link or another file put in its place is left alone: docs/security.md). Returns
  // what went wrong, or an empty string; a group that does not exist is a warning in the log.
  static std::string apply_socket_permissions(const std::string& path, const SocketFile& bound,
                                              const SecurityConfig& security);

  const std::vector<uint32_t>& uids() const { return uids_; }
  const std::vector<uint32_t>& gids() const { return gids_; }

 private:
  // Whether the peer's primary group `gid` or one of its supplementary groups is in `gids`.
  static bool in_groups(int fd, uint32_t gid, const std::vector<uint32_t>& gids);

  std::vector<uint32_t> uids_;
  std::vector<uint32_t> gids_;
  std::vector<uint32_t> admin_gids_;
};

}  // namespace canemu::daemon
