// libxcan.so's exported functions: each checks its handle and arguments, then forwards the
// service 1:1 to canemud (ipc::XcanRequest).
#include <cstring>

#include "xcan_core.hpp"

using canemu::client::xcan::Library;
namespace ipc = canemu::ipc;

namespace {

// The MDD's program number (mxcan2), and where the manual loads it.
constexpr USHORT kProgNo = 0x803A;
constexpr USHORT kSlot = 1;
constexpr USHORT kLayer = 0;

ULONG request(const Library::Handle& channel, ipc::XcanOp op, ipc::XcanReply& reply,
              uint32_t value = 0, const void* data = nullptr, std::size_t size = 0) {
  auto m = ipc::make_message<ipc::XcanRequest>();
  m.op = static_cast<uint16_t>(op);
  m.channel = channel.remote;
  m.value = value;
  m.size = static_cast<uint16_t>(size);
  if (size > 0) {
    std::memcpy(m.data, data, size);
  }
  if (ULONG e = Library::get().call(m, reply); e != ERR_OK) {
    return e;
  }
  return reply.error;
}

ULONG on_channel(MAX_HANDLE h, ipc::XcanOp op, ipc::XcanReply& reply, uint32_t value = 0,
                 const void* data = nullptr, std::size_t size = 0) {
  auto c = Library::get().find(h, Library::Kind::channel);
  if (!c) {
    return ERR_XCAN_INVALID_HANDLE;
  }
  return request(*c, op, reply, value, data, size);
}

}  // namespace

extern "C" {

XCANAPI ULONG canemu_xcan_connect(const char* pszSocket) {
  return Library::get().reconnect(pszSocket != nullptr ? pszSocket : "");
}

XCANAPI ULONG canemu_xcan_enum_interfaces(ULONG ulIndex, CANEMU_XCAN_INTERFACE* pInfo) {
  if (pInfo == nullptr) {
    return ERR_XCAN_NO_MODULE;
  }
  std::vector<CANEMU_XCAN_INTERFACE> found;
  if (ULONG e = Library::get().interfaces(found); e != ERR_OK) {
    return e;
  }
  if (ulIndex >= found.size()) {
    return ERR_XCAN_NO_MODULE;
  }
  *pInfo = found[ulIndex];
  return ERR_OK;
}

XCANAPI ULONG canemu_xcan_callback_time(unsigned long long* pullTime) {
  const auto at = Library::callback_time();
  if (!at || pullTime == nullptr) {
    return ERR_XCAN_NOT_READY;
  }
  *pullTime = static_cast<unsigned long long>(*at);
  return ERR_OK;
}

XCANAPI ULONG canemu_open_module(const char* pszDevice, MAX_HANDLE* phModul) {
  if (pszDevice == nullptr || phModul == nullptr || std::strlen(pszDevice) >= ipc::kNameSize) {
    return ERR_XCAN_NO_MODULE;
  }
  Library::Handle h;
  h.kind = Library::Kind::module;
  h.device = pszDevice;
  auto m = ipc::make_message<ipc::XcanRequest>();
  m.op = static_cast<uint16_t>(ipc::XcanOp::module_check);
  ipc::copy_name(m.device, h.device);
  ipc::XcanReply reply{};
  if (ULONG e = Library::get().call(m, reply); e != ERR_OK) {
    return e;
  }
  *phModul = Library::get().add(std::move(h));
  return *phModul != 0 ? ERR_OK : ERR_XCAN_NO_MEMORY;
}

XCANAPI ULONG max_load_mdd(MAX_HANDLE hModul, USHORT usSlot, USHORT usLayer, USHORT usReserved,
                           USHORT usProgNo, const void* pReserved, MAX_HANDLE* phMDD) {
  (void)usReserved;
  (void)pReserved;
  auto module = Library::get().find(hModul, Library::Kind::module);
  if (!module) {
    return ERR_XCAN_INVALID_HANDLE;
  }
  if (phMDD == nullptr || usSlot != kSlot || usLayer != kLayer || usProgNo != kProgNo) {
    return ERR_XCAN_NO_MODULE;
  }
  Library::Handle h = *module;
  h.kind = Library::Kind::mdd;
  *phMDD = Library::get().add(std::move(h));
  return *phMDD != 0 ? ERR_OK : ERR_XCAN_NO_MEMORY;
}

XCANAPI ULONG max_open_channel(MAX_HANDLE hMDD, const CPS_XCAN* pCPS, MAX_CALLBACK pfnCallback,
                               MAX_HANDLE* phChan) {
  auto mdd = Library::get().find(hMDD, Library::Kind::mdd);
  if (!mdd) {
    return ERR_XCAN_INVALID_HANDLE;
  }
  if (pCPS == nullptr || phChan == nullptr) {
    return ERR_XCAN_INVALID_CPS;
  }
  auto m = ipc::make_message<ipc::XcanRequest>();
  m.op = static_cast<uint16_t>(ipc::XcanOp::open);
  m.flags = pfnCallback != nullptr ? ipc::kXcanCallback : 0;
  ipc::copy_name(m.device, mdd->device);
  static_assert(sizeof(CPS_XCAN) == sizeof m.cps);
  std::memcpy(m.cps, pCPS, sizeof m.cps);
  ipc::XcanReply reply{};
  if (ULONG e = Library::get().call(m, reply); e != ERR_OK) {
    return e;
  }
  if (reply.error != ERR_OK) {
    return reply.error;
  }
  Library::Handle h;
  h.kind = Library::Kind::channel;
  h.device = mdd->device;
  h.remote = reply.channel;
  h.callback = pfnCallback;
  *phChan = Library::get().add(std::move(h));
  return *phChan != 0 ? ERR_OK : ERR_XCAN_NO_MEMORY;
}

XCANAPI ULONG max_close_channel(MAX_HANDLE hChan) {
  ipc::XcanReply reply{};
  const ULONG e = on_channel(hChan, ipc::XcanOp::close, reply);
  if (e != ERR_XCAN_INVALID_HANDLE) {
    Library::get().remove(hChan);
  }
  return e;
}

XCANAPI ULONG max_write_channel_block(MAX_HANDLE hChan, ULONG* pulSize, const void* pData) {
  if (pulSize == nullptr || *pulSize > ipc::kXcanDataSize || (pData == nullptr && *pulSize > 0)) {
    return ERR_XCAN_DATA_SIZE;
  }
  ipc::XcanReply reply{};
  return on_channel(hChan, ipc::XcanOp::write_block, reply, 0, pData, *pulSize);
}

XCANAPI ULONG max_read_channel_block(MAX_HANDLE hChan, ULONG* pulSize, void* pData) {
  if (pulSize == nullptr || (pData == nullptr && *pulSize > 0)) {
    return ERR_XCAN_DATA_SIZE;
  }
  ipc::XcanReply reply{};
  const ULONG e = on_channel(hChan, ipc::XcanOp::read_block, reply);
  if (e != ERR_OK) {
    return e;
  }
  if (reply.size > *pulSize) {
    return ERR_XCAN_DATA_SIZE;
  }
  if (reply.size > 0) {
    std::memcpy(pData, reply.data, reply.size);
  }
  *pulSize = reply.size;
  return ERR_OK;
}

XCANAPI ULONG max_write_channel_ulong(MAX_HANDLE hChan, ULONG ulValue) {
  ipc::XcanReply reply{};
  return on_channel(hChan, ipc::XcanOp::write_ulong, reply, ulValue);
}

XCANAPI ULONG max_read_channel_ulong(MAX_HANDLE hChan, ULONG* pulValue) {
  if (pulValue == nullptr) {
    return ERR_XCAN_DATA_SIZE;
  }
  ipc::XcanReply reply{};
  const ULONG e = on_channel(hChan, ipc::XcanOp::read_ulong, reply);
  if (e == ERR_OK) {
    *pulValue = reply.value;
  }
  return e;
}

XCANAPI ULONG max_channel_control(MAX_HANDLE hChan, USHORT usCommand) {
  ipc::XcanReply reply{};
  return on_channel(hChan, ipc::XcanOp::control, reply, usCommand);
}

XCANAPI ULONG max_channel_info(MAX_HANDLE hChan, USHORT usInfo, ULONG* pulInfo) {
  if (pulInfo == nullptr) {
    return ERR_XCAN_DATA_SIZE;
  }
  ipc::XcanReply reply{};
  const ULONG e = on_channel(hChan, ipc::XcanOp::info, reply, usInfo);
  if (e == ERR_OK) {
    *pulInfo = reply.value;
  }
  return e;
}

XCANAPI ULONG max_clear_error(MAX_HANDLE hChan) {
  ipc::XcanReply reply{};
  return on_channel(hChan, ipc::XcanOp::clear_error, reply);
}

}  // extern "C"
