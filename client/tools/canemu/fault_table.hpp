// The faults canemud applied, as `canemu fault list` and `canemu status` show them.
#pragma once

#include <string>

#include <tl/expected.hpp>

#include "canemu/client/connection.hpp"
#include "canemu/ipc/protocol.hpp"

namespace canemu::cli {

// Asks canemud for its fault list; the error's text on failure.
tl::expected<ipc::FaultListReply, std::string> fault_list(client::Connection& c);

// Every fault, one line each under a header line.
void print_faults(const ipc::FaultListReply& r);

// The same as a JSON array on one line.
std::string faults_json(const ipc::FaultListReply& r);

}  // namespace canemu::cli
