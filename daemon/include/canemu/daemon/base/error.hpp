// canemud's errors below the protocol: what the caller can act on (a code), the text a person
// reads, and, where the error is about the configuration, the place in it ("file:line"). The
// control requests turn them into the protocol's ipc::ErrorCode and text; the configuration's
// and scenarios' checkers keep their lists of "file:line:column: key: what is wrong".
#pragma once

#include <cstdint>
#include <ostream>
#include <string>
#include <string_view>
#include <utility>

#include <tl/expected.hpp>

namespace canemu::daemon {

enum class Errc : uint8_t {
  bad_argument,    // what was asked for is not possible as asked (a name, a value, a state)
  not_found,       // no bus, node, bridge or table of that name
  exists,          // something of that name or place is there already
  bad_bit_timing,  // no controller runs at the rate asked for
  unavailable,     // this build or this host cannot (no LCM, no DDS, a socket family refused)
  io,              // the system refused (a file, a socket)
};

struct Error {
  Errc code = Errc::bad_argument;
  std::string text;   // what is wrong, for a person
  std::string where;  // "file:line" in the configuration, or empty
  // The place and the text, as a log line or a reply shows them.
  std::string what() const { return where.empty() ? text : where + ": " + text; }
  // An error reads as what() wherever it is compared with a person's text (tests, logs).
  friend bool operator==(const Error& e, std::string_view shown) { return e.what() == shown; }
  friend std::ostream& operator<<(std::ostream& out, const Error& e) { return out << e.what(); }
};

template <class T = void>
using Result = tl::expected<T, Error>;

inline tl::unexpected<Error> fail(Errc code, std::string text, std::string where = {}) {
  return tl::unexpected(Error{code, std::move(text), std::move(where)});
}

}  // namespace canemu::daemon
