// canemu's extensions of the VCI C API for simulated CAN nodes at run time (canemu_vci.h,
// docs/restbus.md), in all three libraries: the requests of `canemu restbus` and `canemu signal`.
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>

#include "can_api.hpp"
#include "canemu/client/can_nodes.hpp"
#include "canemu_vci.h"

using namespace canemu::client::vci;
namespace ipc = canemu::ipc;
namespace client = canemu::client;

namespace {

// An argument error of this call, with its detail.
HRESULT invalid(std::string detail) {
  set_call_detail(VCI_E_INVALIDARG, std::move(detail));
  return VCI_E_INVALIDARG;
}

// One request of `op` about a signal; its reply.
HRESULT signal_request(ipc::CanNodeOp op, const char* bus, const char* signal, double value,
                       ipc::CanNodeReply& reply) {
  if (bus == nullptr || signal == nullptr) {
    return invalid("the bus and MESSAGE.SIGNAL are needed");
  }
  client::CanNodeRequests requests;
  requests.push_back(client::can_node_request(op));
  if (std::string e = client::name_signal(*requests[0], bus, signal); !e.empty()) {
    return invalid(std::move(e));
  }
  requests[0]->value = value;
  return Library::get().can_nodes(requests, reply);
}

// One request of `op` about the node `node`.
HRESULT node_request(ipc::CanNodeOp op, const char* node, bool on) {
  if (node == nullptr) {
    return invalid("a node is needed");
  }
  client::CanNodeRequests requests;
  requests.push_back(client::can_node_request(op));
  if (std::string e = client::name_can_node(*requests[0], node); !e.empty()) {
    return invalid(std::move(e));
  }
  requests[0]->on = on ? 1 : 0;
  auto reply = std::make_unique<ipc::CanNodeReply>();
  return Library::get().can_nodes(requests, *reply);
}

}  // namespace

static_assert(sizeof(CANEMU_CANNODEINFO) == 80);

extern "C" {

HRESULT VCIAPI canemuLoadCanNodes(const char* pszTables, const char* pszSource) {
  forget_call_detail();  // an earlier call's reason is not this one's
  if (pszTables == nullptr) {
    return invalid("the tables are needed");
  }
  const std::size_t length = std::strlen(pszTables);
  // (The text is made in canemu_client: a std::to_string here would export its template.)
  if (std::string problem = client::can_node_load_problem(length); !problem.empty()) {
    return invalid(problem);
  }
  auto reply = std::make_unique<ipc::CanNodeReply>();
  return Library::get().can_nodes(
      client::can_node_load_requests(std::string(pszTables, length),
                                     pszSource != nullptr ? pszSource : ""),
      *reply);
}

HRESULT VCIAPI canemuEnumCanNodes(UINT32 dwIndex, PCANEMU_CANNODEINFO pInfo) {
  forget_call_detail();  // an earlier call's reason is not this one's
  if (pInfo == nullptr) {
    return VCI_E_INVALIDARG;
  }
  client::CanNodeRequests requests;
  requests.push_back(client::can_node_request(ipc::CanNodeOp::list));
  auto reply = std::make_unique<ipc::CanNodeReply>();
  if (HRESULT hr = Library::get().can_nodes(requests, *reply); hr != VCI_OK) {
    return hr;
  }
  if (dwIndex >= reply->count) {
    return VCI_E_NO_MORE_ITEMS;
  }
  const ipc::CanNodeEntry& e = reply->nodes[dwIndex];
  CANEMU_CANNODEINFO info{};
  std::snprintf(info.szName, sizeof info.szName, "%s", ipc::name_of(e.name).c_str());
  std::snprintf(info.szBus, sizeof info.szBus, "%s", ipc::name_of(e.bus).c_str());
  info.bPowered = e.powered;
  info.dwMessages = e.messages;
  info.qwFrames = e.frames;
  *pInfo = info;
  return VCI_OK;
}

HRESULT VCIAPI canemuPowerCanNode(const char* pszNode, BOOL fOn) {
  forget_call_detail();  // an earlier call's reason is not this one's
  return node_request(ipc::CanNodeOp::power, pszNode, fOn != 0);
}

HRESULT VCIAPI canemuRemoveCanNode(const char* pszNode) {
  forget_call_detail();  // an earlier call's reason is not this one's
  return node_request(ipc::CanNodeOp::remove, pszNode, false);
}

HRESULT VCIAPI canemuSetSignal(const char* pszBus, const char* pszSignal, double dValue) {
  forget_call_detail();  // an earlier call's reason is not this one's
  auto reply = std::make_unique<ipc::CanNodeReply>();
  return signal_request(ipc::CanNodeOp::set_signal, pszBus, pszSignal, dValue, *reply);
}

HRESULT VCIAPI canemuGetSignal(const char* pszBus, const char* pszSignal, double* pdValue) {
  forget_call_detail();  // an earlier call's reason is not this one's
  if (pdValue == nullptr) {
    return invalid("a place for the value is needed");
  }
  auto reply = std::make_unique<ipc::CanNodeReply>();
  if (HRESULT hr = signal_request(ipc::CanNodeOp::get_signal, pszBus, pszSignal, 0, *reply);
      hr != VCI_OK) {
    return hr;
  }
  *pdValue = reply->value;
  return VCI_OK;
}

}  // extern "C"
