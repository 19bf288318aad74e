// A configuration with many buses and controllers, written by a test: `buses` classic CAN buses
// bus0, bus1, ... at 1 Mbit/s and `controllers` IXXAT controllers over them, four to an adapter
// (dev0, dev1, ...; the last one has the rest). Controller k in configuration order is the node
// devD:J (D = k / 4, J = k % 4) on bus k % buses.
#pragma once

#include <cstddef>
#include <string>

#include <fmt/format.h>

namespace canemu::testing {

inline std::string many_buses_config(std::size_t buses, std::size_t controllers,
                                     const std::string& time = "stepped") {
  std::string text = fmt::format("[simulation]\ntime = \"{}\"\n", time);
  for (std::size_t b = 0; b < buses; ++b) {
    text += fmt::format("[[bus]]\nname = \"bus{}\"\nkind = \"can\"\nbitrate = 1000000\n", b);
  }
  for (std::size_t k = 0; k < controllers; k += 4) {
    text += fmt::format(
        "[[device]]\nname = \"dev{}\"\nmodel = \"ixxat-usb-to-can\"\ncontrollers = [", k / 4);
    for (std::size_t j = k; j < controllers && j < k + 4; ++j) {
      text += fmt::format("{}\"bus{}\"", j == k ? "" : ", ", j % buses);
    }
    text += "]\n";
  }
  return text;
}

inline std::string many_buses_node(std::size_t k) {
  return fmt::format("dev{}:{}", k / 4, k % 4);
}

}  // namespace canemu::testing
