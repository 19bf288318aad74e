#include "dump_filter.hpp"

#include <time.h>

#include <cctype>

#include <fmt/format.h>

namespace canemu::cli {

namespace sc = ipc::socketcan;

namespace {

// 1..8 hex digits; nothing otherwise.
std::optional<uint32_t> hex32(std::string_view s) {
  if (s.empty() || s.size() > 8) {
    return std::nullopt;
  }
  uint32_t v = 0;
  for (char ch : s) {
    if (!std::isxdigit(static_cast<unsigned char>(ch))) {
      return std::nullopt;
    }
    const int d =
        std::isdigit(static_cast<unsigned char>(ch)) ? ch - '0' : std::tolower(ch) - 'a' + 10;
    v = (v << 4) | static_cast<uint32_t>(d);
  }
  return v;
}

// <id>:<mask> or <id>~<mask> as candump puts it into a struct can_filter and the kernel keeps
// it (af_can.c, can_rcv_list_find).
std::optional<CanFilter> can_filter(std::string_view text) {
  const std::size_t sep = text.find_first_of(":~");
  if (sep == std::string_view::npos) {
    return std::nullopt;
  }
  const auto id_text = text.substr(0, sep);
  auto id = hex32(id_text);
  auto mask = hex32(text.substr(sep + 1));
  if (!id || !mask) {
    return std::nullopt;
  }
  // candump: an identifier of 8 digits is a 29-bit one; a mask never asks for CAN_ERR_FLAG
  // (that would make it an error filter); ~ sets CAN_INV_FILTER (the same bit as
  // CAN_ERR_FLAG, so an <id> with it set is inverted too).
  if (id_text.size() == 8) {
    *id |= sc::kEffFlag;
  }
  *mask &= ~sc::kErrFlag;
  if (text[sep] == '~') {
    *id |= kInvFilter;
  }
  CanFilter f;
  f.inverted = (*id & kInvFilter) != 0;
  f.text = std::string(text);
  // The kernel: a mask with CAN_EFF_FLAG and an identifier without it asks for 11-bit frames
  // only; the identifier is kept masked.
  if ((*mask & sc::kEffFlag) != 0 && (*id & sc::kEffFlag) == 0) {
    *mask &= sc::kSffMask | sc::kEffFlag | sc::kRtrFlag;
  }
  f.mask = *mask;
  f.id = *id & *mask;
  return f;
}

}  // namespace

bool BusFilter::matches(const sc::Frame& f) const {
  if ((f.can_id & sc::kErrFlag) != 0) {
    // Error frames: by their classes alone (the kernel's separate error filter), also with
    // joined filters.
    return (f.can_id & error_mask & kErrMask) != 0;
  }
  if (filters.empty()) {
    return true;  // candump's default filter 0:0
  }
  for (const CanFilter& c : filters) {
    if (c.matches(f.can_id) != join) {
      return !join;  // one matches (any), or one does not (join)
    }
  }
  return join;
}

std::string BusFilter::describe() const {
  if (!filtered) {
    return {};
  }
  std::string what;
  if (filters.empty()) {
    what = "every frame";
  } else {
    what = "frames that match ";
    for (std::size_t i = 0; i < filters.size(); ++i) {
      what += (i == 0 ? "" : join ? " and " : " or ") + filters[i].text;
    }
  }
  if (error_mask == 0) {
    return what + "; no error frames (#<mask> selects them)";
  }
  return what + fmt::format("; error frames of classes {:08X}", error_mask);
}

std::optional<BusFilter> parse_bus_filter(std::string_view arg, std::string& error) {
  const std::size_t comma = arg.find(',');
  BusFilter b;
  b.text = std::string(arg);
  b.bus = std::string(arg.substr(0, comma));
  if (b.bus.empty()) {
    error = fmt::format("'{}': no bus name before the filters (candump's <bus>[,filter]*)", arg);
    return std::nullopt;
  }
  if (comma == std::string_view::npos) {
    return b;
  }
  b.filtered = true;
  b.error_mask = 0;  // a filter list takes error frames by #<mask> only
  std::string_view rest = arg.substr(comma + 1);
  for (;;) {
    const std::size_t next = rest.find(',');
    const std::string_view item = rest.substr(0, next);
    if (item == "j" || item == "J") {
      b.join = true;
    } else if (!item.empty() && item[0] == '#' && hex32(item.substr(1))) {
      b.error_mask = *hex32(item.substr(1)) & kErrMask;
    } else if (auto f = can_filter(item)) {
      b.filters.push_back(std::move(*f));
    } else {
      error = fmt::format(
          "'{}': filter '{}' is not <id>:<mask>, <id>~<mask>, #<error mask> or j "
          "(hex, as candump takes them)",
          arg, item);
      return std::nullopt;
    }
    if (next == std::string_view::npos) {
      return b;
    }
    rest = rest.substr(next + 1);
  }
}

std::string candump_log_name(int64_t t) {
  const time_t seconds = static_cast<time_t>(t);
  struct tm now {};
  ::localtime_r(&seconds, &now);
  return fmt::format("candump-{:04}-{:02}-{:02}_{:02}{:02}{:02}.log", now.tm_year + 1900,
                     now.tm_mon + 1, now.tm_mday, now.tm_hour, now.tm_min, now.tm_sec);
}

}  // namespace canemu::cli
