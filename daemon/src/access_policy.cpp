#include "canemu/daemon/access_policy.hpp"

#include <algorithm>
#include <cerrno>

#include <grp.h>
#include <pwd.h>
#include <sys/socket.h>
#include <unistd.h>

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
    } else {
      log::warning("[security] group \"{}\" does not exist", g);
    }
  }
}

bool AccessPolicy::allowed(int fd, uint32_t uid) const {
  if (uid == 0 || uid == ::geteuid()) {
    return true;
  }
  if (std::find(uids_.begin(), uids_.end(), uid) != uids_.end()) {
    return true;
  }
  if (gids_.empty()) {
    return false;
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

}  // namespace canemu::daemon
