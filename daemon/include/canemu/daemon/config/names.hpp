// The rules for names and addresses in canemud's configuration that other parts check too:
// DDS domains, partitions and topic prefixes, LCM URLs and channel prefixes, and this daemon's
// name among others. The configuration reader, `canemu bridge add` and the bridges themselves
// all ask these functions, so that a name is refused with the same words wherever it is given.
// Each *_problem function returns what is wrong, or nothing.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace canemu::daemon {

// ---- DDS (the DDS bridge, [distributed]) ----
inline constexpr uint32_t kMaxDdsDomain = 232;  // the highest id RTPS's port mapping allows
inline constexpr std::string_view kDefaultDdsPartition = "canemu";
inline constexpr std::size_t kMaxDdsPartition = 63;
inline constexpr std::size_t kMaxDdsPrefix = 63;

// canemu/<bus>/: the bus's name with anything but letters, digits and '_' as '_'.
std::string default_dds_prefix(std::string_view bus);
// What is wrong with a topic prefix: 1 to 63 characters, letters, digits, '_' and '/', not
// starting with a digit.
std::optional<std::string> dds_prefix_problem(std::string_view prefix);
// What is wrong with a partition: 1 to 63 printable characters, no blanks, no wildcards (* ?).
std::optional<std::string> dds_partition_problem(std::string_view partition);
// What is wrong with a domain id (0..232).
std::optional<std::string> dds_domain_problem(int64_t domain);

// ---- LCM (the LCM bridge) ----
// Packets with TTL 0 never leave the host.
inline constexpr std::string_view kDefaultLcmUrl = "udpm://239.255.76.67:7667?ttl=0";
inline constexpr std::size_t kMaxLcmUrl = 127;
inline constexpr std::size_t kMaxLcmPrefix = 63;

// CANEMU_<BUS>_: the bus's name in capitals, anything but letters, digits and '_' as '_'
// ("can0" -> "CANEMU_CAN0_", "fd-1" -> "CANEMU_FD_1_").
std::string default_lcm_prefix(std::string_view bus);
// What is wrong with a channel prefix: 1 to 63 characters, letters, digits, '_', '-', '.', '/'.
std::optional<std::string> lcm_prefix_problem(std::string_view prefix);
// What is wrong with a provider URL as far as canemud can tell before opening it (LCM opens it):
// 1 to 127 characters, "provider://...".
std::optional<std::string> lcm_url_problem(std::string_view url);

// ---- buses across hosts ----
// The name a daemon goes by when [distributed] gives none: the host name up to its first '.',
// lower case, every character a name may not have made '-', at most 28 characters.
std::string default_daemon_name();

}  // namespace canemu::daemon
