#include "canemu/daemon/loop/access_policy.hpp"

#include <algorithm>
#include <cerrno>
#include <cstring>

#include <fcntl.h>
#include <grp.h>
#include <pwd.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <unistd.h>

#include <fmt/format.h>

#include "canemu/daemon/base/log.hpp"
#include "canemu/ipc/unique_fd.hpp"

namespace canemu::daemon {

namespace {

// The groups named, by gid; names that do not exist are logged (except the default group).
std::vector<uint32_t> resolve_groups(const std::vector<std::string>& names, const char* key) {
  std::vector<uint32_t> gids;
  for (const std::string& g : names) {
    if (const group* gr = ::getgrnam(g.c_str())) {
      gids.push_back(gr->gr_gid);
    } else if (g != kServiceGroup) {
      // (The default group missing is normal on a machine without the packages' sysusers file.)
      log::warning("[security] {}: group \"{}\" does not exist", key, g);
    }
  }
  return gids;
}

}  // namespace

void AccessPolicy::resolve(const SecurityConfig& security) {
  uids_.clear();
  for (const std::string& u : security.allowed_users) {
    if (const passwd* pw = ::getpwnam(u.c_str())) {
      uids_.push_back(pw->pw_uid);
    } else {
      log::warning("[security] user \"{}\" does not exist", u);
    }
  }
  gids_ = resolve_groups(security.allowed_groups, "allowed_groups");
  admin_gids_ = resolve_groups(security.admin_groups, "admin_groups");
}

bool AccessPolicy::allowed(int fd, uint32_t uid, uint32_t gid) const {
  if (uid == 0 || uid == ::geteuid()) {
    return true;
  }
  if (std::find(uids_.begin(), uids_.end(), uid) != uids_.end()) {
    return true;
  }
  return in_groups(fd, gid, gids_);
}

bool AccessPolicy::admin(int fd, uint32_t uid, uint32_t gid) const {
  return uid == 0 || uid == ::geteuid() || in_groups(fd, gid, admin_gids_);
}

bool AccessPolicy::in_groups(int fd, uint32_t gid, const std::vector<uint32_t>& gids) {
  if (gids.empty()) {
    return false;
  }
  if (std::find(gids.begin(), gids.end(), gid) != gids.end()) {
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
    if (std::find(gids.begin(), gids.end(), g) != gids.end()) {
      return true;
    }
  }
  return false;
}

Result<AccessPolicy::SocketFile> AccessPolicy::socket_file(const std::string& path) {
  struct stat st {};
  if (::lstat(path.c_str(), &st) != 0) {
    return fail(Errc::io, fmt::format("cannot look at {}: {}", path, std::strerror(errno)));
  }
  if (!S_ISSOCK(st.st_mode)) {
    return fail(Errc::bad_argument, fmt::format("{} is not a socket", path));
  }
  return SocketFile{static_cast<uint64_t>(st.st_dev), static_cast<uint64_t>(st.st_ino)};
}

std::string AccessPolicy::apply_socket_permissions(const std::string& path, const SocketFile& bound,
                                                   const SecurityConfig& security) {
  // The file itself, never what a link at its place points to: a descriptor of the path (not
  // followed), checked to be the socket that was bound, and changed through that descriptor.
  const int fd = ::open(path.c_str(), O_PATH | O_NOFOLLOW | O_CLOEXEC);
  if (fd < 0) {
    return fmt::format("cannot open {}: {}; its mode and group are left as they are", path,
                       std::strerror(errno));
  }
  const ipc::UniqueFd file(fd);
  struct stat st {};
  if (::fstat(fd, &st) != 0 || !S_ISSOCK(st.st_mode) ||
      static_cast<uint64_t>(st.st_dev) != bound.dev ||
      static_cast<uint64_t>(st.st_ino) != bound.ino) {
    return fmt::format(
        "{} is no longer the socket canemud bound ({} is there now); its mode and group are left "
        "as they are",
        path,
        S_ISLNK(st.st_mode)    ? "a symbolic link"
        : S_ISSOCK(st.st_mode) ? "another socket"
                               : "another file");
  }
  if (!security.socket_group.empty()) {
    if (const group* gr = ::getgrnam(security.socket_group.c_str())) {
      if (::fchownat(fd, "", static_cast<uid_t>(-1), gr->gr_gid, AT_EMPTY_PATH) != 0) {
        return fmt::format("cannot give {} to group {}: {}", path, security.socket_group,
                           std::strerror(errno));
      }
    } else if (security.socket_group != kServiceGroup) {
      log::warning("[security] socket_group \"{}\" does not exist; {} stays in group {}",
                   security.socket_group, path, ::getegid());
    }
  }
  // chmod has no form for a descriptor opened with O_PATH; /proc names that very file.
  if (::chmod(fmt::format("/proc/self/fd/{}", fd).c_str(),
              static_cast<mode_t>(security.socket_mode)) != 0) {
    return fmt::format("cannot set mode {:04o} on {}: {}", security.socket_mode, path,
                       std::strerror(errno));
  }
  return {};
}

}  // namespace canemu::daemon
