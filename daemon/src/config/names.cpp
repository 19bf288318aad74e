#include "canemu/daemon/config/names.hpp"

#include <unistd.h>

#include <cctype>
#include <cstring>

#include <fmt/format.h>

namespace canemu::daemon {

std::string default_dds_prefix(std::string_view bus) {
  std::string p = "canemu/";
  for (char ch : bus) {
    p += std::isalnum(static_cast<unsigned char>(ch)) ? ch : '_';
  }
  return p + "/";
}

std::optional<std::string> dds_prefix_problem(std::string_view prefix) {
  const bool length_ok = !prefix.empty() && prefix.size() <= kMaxDdsPrefix;
  bool chars_ok = length_ok && !std::isdigit(static_cast<unsigned char>(prefix[0]));
  for (char ch : prefix) {
    chars_ok = chars_ok && (std::isalnum(static_cast<unsigned char>(ch)) || ch == '_' || ch == '/');
  }
  if (!chars_ok) {
    return fmt::format(
        "\"{}\" is not a topic prefix (1 to {} letters, digits, '_' and '/', not starting with a "
        "digit)",
        prefix, kMaxDdsPrefix);
  }
  return std::nullopt;
}

std::optional<std::string> dds_partition_problem(std::string_view partition) {
  bool ok = !partition.empty() && partition.size() <= kMaxDdsPartition;
  for (char ch : partition) {
    const auto u = static_cast<unsigned char>(ch);
    ok = ok && u > ' ' && u < 0x7F && ch != '*' && ch != '?' && ch != '+' && ch != '/';
  }
  if (!ok) {
    return fmt::format(
        "\"{}\" is not a partition (1 to {} printable characters; no blanks, '*', '?', '+' or "
        "'/')",
        partition, kMaxDdsPartition);
  }
  return std::nullopt;
}

std::optional<std::string> dds_domain_problem(int64_t domain) {
  if (domain < 0 || domain > kMaxDdsDomain) {
    return fmt::format("{} is not a DDS domain id (0 to {})", domain, kMaxDdsDomain);
  }
  return std::nullopt;
}

std::string default_lcm_prefix(std::string_view bus) {
  std::string p = "CANEMU_";
  for (char ch : bus) {
    const auto u = static_cast<unsigned char>(ch);
    p += std::isalnum(u) ? static_cast<char>(std::toupper(u)) : '_';
  }
  return p + "_";
}

std::optional<std::string> lcm_prefix_problem(std::string_view prefix) {
  if (prefix.empty() || prefix.size() > kMaxLcmPrefix) {
    return "\"" + std::string(prefix) + "\" is not a channel prefix (1 to " +
           std::to_string(kMaxLcmPrefix) + " characters)";
  }
  for (char ch : prefix) {
    if (!std::isalnum(static_cast<unsigned char>(ch)) && std::strchr("_-./", ch) == nullptr) {
      return "\"" + std::string(prefix) +
             "\" is not a channel prefix (letters, digits, '_', '-', '.', '/')";
    }
  }
  return std::nullopt;
}

std::optional<std::string> lcm_url_problem(std::string_view url) {
  const auto scheme = url.find("://");
  if (url.size() > kMaxLcmUrl || scheme == std::string_view::npos || scheme == 0) {
    return "\"" + std::string(url) + "\" is not an LCM URL (provider://network?options, up to " +
           std::to_string(kMaxLcmUrl) + " characters)";
  }
  for (char ch : url) {
    if (static_cast<unsigned char>(ch) <= ' ') {
      return "\"" + std::string(url) + "\" is not an LCM URL (no blanks)";
    }
  }
  return std::nullopt;
}

std::string default_daemon_name() {
  char host[256] = {};
  if (::gethostname(host, sizeof host - 1) != 0 || host[0] == '\0') {
    return "canemud";
  }
  std::string name;
  for (const char* p = host; *p != '\0' && *p != '.' && name.size() < 28; ++p) {
    const auto ch = static_cast<unsigned char>(std::tolower(static_cast<unsigned char>(*p)));
    name += std::isalnum(ch) || ch == '_' || ch == '-' ? static_cast<char>(ch) : '-';
  }
  return name.empty() ? std::string("canemud") : name;
}

}  // namespace canemu::daemon
