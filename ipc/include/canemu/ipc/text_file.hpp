// Text files that a person names (a configuration, a scenario, an EEPROM image): read whole, but
// never more than a stated size, so that a directory, a device without end (/dev/zero) or a huge
// file gets an error that says so instead of filling the memory.
#pragma once

#include <cstddef>
#include <string>

#include <tl/expected.hpp>

namespace canemu::ipc {

// The text of the file at `path` (a regular file, a pipe or a device that ends), at most
// `max_bytes`; else a message that names the file and what is wrong with it.
tl::expected<std::string, std::string> read_text_file(const std::string& path,
                                                      std::size_t max_bytes);

}  // namespace canemu::ipc
