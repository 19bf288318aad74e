// The text of VCI results (VciFormatError, vciFormatError) and the detail of the last failure
// of each thread that goes with it.
#include <string>

#include <fmt/format.h>

#include "vci_core.hpp"

namespace canemu::client::vci {

namespace {

thread_local std::string t_detail;
thread_local bool t_call_detail = false;  // t_detail is set_call_detail's, for t_call_hr only
thread_local HRESULT t_call_hr = VCI_OK;

}  // namespace

void set_detail(std::string detail) {
  t_detail = std::move(detail);
  t_call_detail = false;
}

void set_call_detail(HRESULT hr, std::string detail) {
  t_detail = std::move(detail);
  t_call_detail = true;
  t_call_hr = hr;
}

void forget_call_detail() {
  if (t_call_detail) {
    t_detail.clear();
    t_call_detail = false;
  }
}

std::string format_error(HRESULT hr) {
  const auto code = static_cast<uint32_t>(hr);
  std::string text;
  switch (code) {
    case static_cast<uint32_t>(VCI_OK):
      text = "success";
      break;
    case static_cast<uint32_t>(VCI_E_UNEXPECTED):
      text = "unexpected error";
      break;
    case static_cast<uint32_t>(VCI_E_NOT_IMPLEMENTED):
      text = "function not implemented";
      break;
    case static_cast<uint32_t>(VCI_E_OUTOFMEMORY):
      text = "not enough memory or resources";
      break;
    case static_cast<uint32_t>(VCI_E_INVALIDARG):
      text = "invalid argument";
      break;
    case static_cast<uint32_t>(VCI_E_NOINTERFACE):
      text = "interface not supported";
      break;
    case static_cast<uint32_t>(VCI_E_INVPOINTER):
      text = "invalid pointer";
      break;
    case static_cast<uint32_t>(VCI_E_INVHANDLE):
      text = "invalid handle";
      break;
    case static_cast<uint32_t>(VCI_E_ABORT):
      text = "operation aborted";
      break;
    case static_cast<uint32_t>(VCI_E_FAIL):
      text = "operation failed";
      break;
    case static_cast<uint32_t>(VCI_E_ACCESSDENIED):
      text = "access denied: the object is in use";
      break;
    case static_cast<uint32_t>(VCI_E_TIMEOUT):
      text = "timeout";
      break;
    case static_cast<uint32_t>(VCI_E_BUSY):
      text = "busy";
      break;
    case static_cast<uint32_t>(VCI_E_PENDING):
      text = "pending";
      break;
    case static_cast<uint32_t>(VCI_E_NO_DATA):
      text = "no data";
      break;
    case static_cast<uint32_t>(VCI_E_NO_MORE_ITEMS):
      text = "no more items";
      break;
    case static_cast<uint32_t>(VCI_E_NOT_INITIALIZED):
      text = "not initialized";
      break;
    case static_cast<uint32_t>(VCI_E_ALREADY_INITIALIZED):
      text = "already initialized";
      break;
    case static_cast<uint32_t>(VCI_E_RXQUEUE_EMPTY):
      text = "receive queue empty";
      break;
    case static_cast<uint32_t>(VCI_E_TXQUEUE_FULL):
      text = "transmit queue full";
      break;
    case static_cast<uint32_t>(VCI_E_BUFFER_OVERFLOW):
      text = "buffer too small";
      break;
    case static_cast<uint32_t>(VCI_E_INVALID_STATE):
      text = "invalid state";
      break;
    case static_cast<uint32_t>(VCI_E_OBJECT_ALREADY_EXISTS):
      text = "object already exists";
      break;
    case static_cast<uint32_t>(VCI_E_INVALID_INDEX):
      text = "invalid index";
      break;
    case static_cast<uint32_t>(VCI_E_END_OF_FILE):
      text = "end of file";
      break;
    case static_cast<uint32_t>(VCI_E_DISCONNECTED):
      text = "disconnected from canemud";
      break;
    case static_cast<uint32_t>(VCI_E_WRONG_FLASHFWVERSION):
      text = "wrong flash firmware version";
      break;
    case static_cast<uint32_t>(VCI_E_INVALID_LICENSE):
      text = "invalid license";
      break;
    case static_cast<uint32_t>(VCI_E_NO_SUCH_LICENSE):
      text = "no license available";
      break;
    case static_cast<uint32_t>(VCI_E_LICENSE_EXPIRED):
      text = "license expired";
      break;
    case static_cast<uint32_t>(VCI_E_LICENSE_QUOTA_EXCEEDED):
      text = "license quota exceeded";
      break;
    case static_cast<uint32_t>(VCI_E_INVALID_TIMING):
      text = "invalid bit timing";
      break;
    case static_cast<uint32_t>(VCI_E_IN_USE):
      text = "resource in use";
      break;
    case static_cast<uint32_t>(VCI_E_NO_SUCH_DEVICE):
      text = "no such device";
      break;
    case static_cast<uint32_t>(VCI_E_DEVICE_NOT_CONNECTED):
      text = "device not connected";
      break;
    case static_cast<uint32_t>(VCI_E_DEVICE_NOT_READY):
      text = "device not ready";
      break;
    case static_cast<uint32_t>(VCI_E_TYPE_MISMATCH):
      text = "wrong type of object";
      break;
    case static_cast<uint32_t>(VCI_E_NOT_SUPPORTED):
      text = "request not supported";
      break;
    case static_cast<uint32_t>(VCI_E_DUPLICATE_OBJECTID):
      text = "object id already in use";
      break;
    case static_cast<uint32_t>(VCI_E_OBJECTID_NOT_FOUND):
      text = "object id not found";
      break;
    case static_cast<uint32_t>(VCI_E_WRONG_LEVEL):
      text = "called at the wrong execution level";
      break;
    case static_cast<uint32_t>(VCI_E_WRONG_DRV_VERSION):
      text = "incompatible driver version";
      break;
    case static_cast<uint32_t>(VCI_E_LUIDS_EXHAUSTED):
      text = "no more LUIDs";
      break;
    default:
      text = fmt::format("unknown error {:#010x}", code);
      break;
  }
  if (hr != VCI_OK && !t_detail.empty() && (!t_call_detail || hr == t_call_hr)) {
    text += " (" + t_detail + ")";
  }
  return text;
}

}  // namespace canemu::client::vci
