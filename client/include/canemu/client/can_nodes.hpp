// Requests about canemud's simulated CAN nodes at run time (ipc::CanNodeRequest,
// docs/restbus.md), shared by `canemu restbus` / `canemu signal` and the VCI libraries'
// extension calls: a load cut into its parts, a signal named MESSAGE.SIGNAL, and the parts sent
// in turn.
#pragma once

#include <cstddef>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "canemu/client/connection.hpp"
#include "canemu/ipc/protocol.hpp"

namespace canemu::client {

using CanNodeRequests = std::vector<std::unique_ptr<ipc::CanNodeRequest>>;

// A request of `op`, everything else zero.
std::unique_ptr<ipc::CanNodeRequest> can_node_request(ipc::CanNodeOp op);

// The requests of a load of [[can_node]] tables: the text in parts of at most
// ipc::kMaxCanNodeText bytes, the last one `load`, the ones before it `load_part`; `source`
// (the file's name, shown in canemud's errors) in each.
CanNodeRequests can_node_load_requests(const std::string& text, const std::string& source);
// Why a load of `length` bytes cannot go to canemud (longer than ipc::kMaxCanNodeLoad), or "".
std::string can_node_load_problem(std::size_t length);

// The node into `m.name` (power, remove); an error text when it is too long for it.
std::string name_can_node(ipc::CanNodeRequest& m, const std::string& node);

// The bus and MESSAGE.SIGNAL into `m` (set_signal, get_signal); an error text when `signal` is
// not MESSAGE.SIGNAL or a name is too long.
std::string name_signal(ipc::CanNodeRequest& m, const std::string& bus, const std::string& signal);

// What became of the requests: `reply` is the last one's when every part was taken. Otherwise
// `refused` is canemud's reason (one line per error, without the last newline: nothing
// changed), or `error` says why canemud could not be asked.
struct CanNodeOutcome {
  std::unique_ptr<ipc::CanNodeReply> reply;
  std::string refused;
  std::optional<IpcError> error;
};

// Sends the requests in order over `c`, stopping at the first that is not taken. A load's parts
// must all go over one connection.
CanNodeOutcome call_can_nodes(Connection& c, const CanNodeRequests& requests);

}  // namespace canemu::client
