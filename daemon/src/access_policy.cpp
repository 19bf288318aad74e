#include "canemu/daemon/access_policy.hpp"

#include <algorithm>
#include <cerrno>
#include <cstring>

#include <grp.h>
#include <pwd.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <unistd.h>

#include <fmt/format.h>

#include "canemu/daemon/log.hpp"

namespace canemu::daemon {

void AccessPolicy::resolve(const SecurityConfig& security) {
  uids_.clear();
  gids_.clear();
  for (const std::string& u : security.allowed_users) {
    if (const passwd* pw = ::getpwnam(u.c_str())) {
      uids_.push_back(pw->pw_uid);
    } else {
      log::warning("[security] user \"{}\" does not exist", u);
    }
  }
  for (const std::string& g : security.allowed_groups) {
    if (const group* gr = ::getgrnam(g.c_str())) {
      gids_.push_back(gr->gr_gid);
    } else if (g != kServiceGroup) {
      // (The default group missing is normal on a machine without the packages' sysusers file.)
      log::warning("[security] group \"{}\" does not exist", g);
    }
  }
}

bool AccessPolicy::allowed(int fd, uint32_t uid, uint32_t gid) const {
  if (uid == 0 || uid == ::geteuid()) {
    return true;
  }
  if (std::find(uids_.begin(), uids_.end(), uid) != uids_.end()) {
    return true;
  }
  if (gids_.empty()) {
    return false;
  }
  if (std::find(gids_.begin(), gids_.end(), gid) != gids_.end()) {
    return true;  // the primary group, which SO_PEERGROUPS need not list
  }
  // The peer's groups from the kernel (SO_PEERGROUPS): no user database lookups in the loop.
  std::vector<gid_t> groups(64);
  socklen_t len = static_cast<socklen_t>(groups.size() * sizeof(gid_t));
  if (::getsockopt(fd, SOL_SOCKET, SO_PEERGROUPS, groups.data(), &len) != 0) {
    if (errno != ERANGE) {
      return false;
    }
    groups.resize(len / sizeof(gid_t));
    if (::getsockopt(fd, SOL_SOCKET, SO_PEERGROUPS, groups.data(), &len) != 0) {
      return false;
    }
  }
  groups.resize(len / sizeof(gid_t));
  for (gid_t g : groups) {
    if (std::find(gids_.begin(), gids_.end(), g) != gids_.end()) {
      return true;
    }
  }
  return false;
}

std::string AccessPolicy::apply_socket_permissions(const std::string& path,
                                                   const SecurityConfig& security) {
  if (!security.socket_group.empty()) {
    if (const group* gr = ::getgrnam(security.socket_group.c_str())) {
      if (::chown(path.c_str(), static_cast<uid_t>(-1), gr->gr_gid) != 0) {
        return fmt::format("cannot give {} to group {}: {}", path, security.socket_group,
                           std::strerror(errno));
      }
    } else if (security.socket_group != kServiceGroup) {
      log::warning("[security] socket_group \"{}\" does not exist; {} stays in group {}",
                   security.socket_group, path, ::getegid());
    }
  }
  if (::chmod(path.c_str(), static_cast<mode_t>(security.socket_mode)) != 0) {
    return fmt::format("cannot set mode {:04o} on {}: {}", security.socket_mode, path,
                       std::strerror(errno));
  }
  return {};
}

}  // namespace canemu::daemon
