// The VCI C++ API (vcisdk.h) over the same core as the C libraries: its exported functions
// and interface identifiers. The reference-counted objects they hand out, which hold the
// core's remote objects and rings, live in com.hpp (the IUnknown part), device_objects
// (device manager, enumerator, device, BAL), can_objects (socket, control unit, channel,
// cyclic list) and fifo_objects (readers, writers, stand-alone FIFOs).
#include <cinttypes>
#include <cstdio>
#include <memory>

#include <sys/utsname.h>

#include "com.hpp"
#include "device_objects.hpp"
#include "fifo_objects.hpp"
#include "vci_core.hpp"
#include "vcisdk.h"

using namespace canemu::client::vci;
using namespace canemu::client::vci::cpp;
using canemu::ipc::VciOp;

// ---------------------------------------------------------------- identifiers

namespace {
// canemu's interface and class identifiers: one family, the last byte numbering them.
constexpr GUID guid(uint8_t n) {
  return GUID{0x3b1f7c02U, 0x6a5e, 0x4d21, {0x8c, 0x3a, 0x27, 0x90, 0x5e, 0x11, 0xc4, n}};
}
}  // namespace

extern "C" {
const IID IID_IUnknown = {0x00000000U, 0x0000, 0x0000, {0xc0, 0, 0, 0, 0, 0, 0, 0x46}};
const IID IID_IVciDeviceManager = guid(1);
const IID IID_IVciEnumDevice = guid(2);
const IID IID_IVciDevice = guid(3);
const IID IID_IBalObject = guid(4);
const IID IID_ICanSocket = guid(5);
const IID IID_ICanSocket2 = guid(6);
const IID IID_ICanControl = guid(7);
const IID IID_ICanControl2 = guid(8);
const IID IID_ICanChannel = guid(9);
const IID IID_ICanChannel2 = guid(10);
const IID IID_ICanScheduler = guid(11);
const IID IID_ICanScheduler2 = guid(12);
const IID IID_IFifoReader = guid(13);
const IID IID_IFifoWriter = guid(14);
const IID IID_IVciFifo = guid(15);
const IID IID_IVciFifo2 = guid(16);
const IID IID_ILinSocket = guid(17);
const IID IID_ILinControl = guid(18);
const IID IID_ILinMonitor = guid(19);
const CLSID CLSID_VCIBAL = guid(0x80);
}

// ---------------------------------------------------------------- functions

extern "C" {

HRESULT VCIAPI VciInitialize(void) {
  return VCI_OK;
}

HRESULT VCIAPI VciFormatError(HRESULT hrError, PTCHAR pszError, UINT32 dwLength) {
  if (pszError == nullptr || dwLength == 0) {
    return VCI_E_INVALIDARG;
  }
  std::snprintf(pszError, dwLength, "%s", format_error(hrError).c_str());
  return VCI_OK;
}

HRESULT VCIAPI VciGetVersion(PVCIVERSIONINFO p) {
  if (p == nullptr) {
    return VCI_E_INVALIDARG;
  }
  *p = VCIVERSIONINFO{};
  p->VciMajorVersion = kVciMajorVersion;
  p->VciMinorVersion = kVciMinorVersion;
  p->VciReleaseNumber = kVciRevisionNumber;
  p->VciBuildNumber = vci_build_number();
  // The kernel's version ("6.1.0-18-amd64": 6, 1, 0); the platform id stays 0 (not Windows).
  utsname u{};
  if (::uname(&u) == 0) {
    std::sscanf(u.release, "%" SCNu32 ".%" SCNu32 ".%" SCNu32, &p->OsMajorVersion,
                &p->OsMinorVersion, &p->OsBuildNumber);
  }
  return VCI_OK;
}

HRESULT VCIAPI VciCreateLuid(PVCIID p) {
  if (p == nullptr) {
    return VCI_E_INVALIDARG;
  }
  p->AsInt64 = new_luid();
  return VCI_OK;
}

HRESULT VCIAPI VciLuidToChar(REFVCIID rVciid, PCHAR psz, LONG cbSize) {
  return copy_text(luid_text(rVciid), psz, cbSize);
}

HRESULT VCIAPI VciCharToLuid(PCHAR psz, PVCIID p) {
  if (psz == nullptr || p == nullptr) {
    return VCI_E_INVALIDARG;
  }
  const auto id = parse_luid(psz);
  if (!id) {
    return VCI_E_FAIL;
  }
  *p = *id;
  return VCI_OK;
}

HRESULT VCIAPI VciGuidToChar(REFGUID g, PCHAR psz, LONG cbSize) {
  return copy_text(guid_text(g), psz, cbSize);
}

HRESULT VCIAPI VciCharToGuid(PCHAR psz, PGUID p) {
  if (psz == nullptr || p == nullptr) {
    return VCI_E_INVALIDARG;
  }
  const auto g = parse_guid(psz);
  if (!g) {
    return VCI_E_FAIL;
  }
  *p = *g;
  return VCI_OK;
}

HRESULT VCIAPI VciGetDeviceManager(IVciDeviceManager** pp) {
  if (!null_out(pp)) {
    return VCI_E_INVALIDARG;
  }
  if (HRESULT hr = Library::get().connect(); hr != VCI_OK) {
    return hr;
  }
  *pp = new_device_manager();
  return VCI_OK;
}

HRESULT VCIAPI VciQueryDeviceByHwid(REFGUID rHwid, IVciDevice** pp) {
  if (!null_out(pp)) {
    return VCI_E_INVALIDARG;
  }
  HRESULT hr = VCI_OK;
  if (auto d = device_by_hwid(rHwid, hr)) {
    *pp = new_device(std::move(*d));
  }
  return hr;
}

HRESULT VCIAPI VciQueryDeviceByClass(REFGUID rClass, UINT32 dwInst, IVciDevice** pp) {
  if (!null_out(pp)) {
    return VCI_E_INVALIDARG;
  }
  HRESULT hr = VCI_OK;
  if (auto d = device_by_class(rClass, dwInst, hr)) {
    *pp = new_device(std::move(*d));
  }
  return hr;
}

HRESULT VCIAPI VciCreateFifo(PVCIID pResid, UINT16 wCapacity, UINT16 wElementSize, REFIID riid,
                             PVOID* ppv) {
  if (!null_out(ppv) || pResid == nullptr || wCapacity == 0 || wElementSize == 0) {
    return VCI_E_INVALIDARG;
  }
  std::shared_ptr<SharedFifo> fifo;
  if (HRESULT hr = shared_fifo(VciOp::fifo_create, wCapacity, wElementSize, fifo); hr != VCI_OK) {
    return hr;
  }
  pResid->AsInt64 = static_cast<INT64>(fifo->id);
  return open_fifo(fifo, riid, ppv);
}

HRESULT VCIAPI VciAccessFifo(REFVCIID rResid, REFIID riid, PVOID* ppv) {
  if (!null_out(ppv)) {
    return VCI_E_INVALIDARG;
  }
  const auto id = static_cast<uint64_t>(rResid.AsInt64);
  std::shared_ptr<SharedFifo> fifo;
  if (HRESULT hr = shared_fifo(VciOp::fifo_access, static_cast<uint32_t>(id),
                               static_cast<uint32_t>(id >> 32), fifo);
      hr != VCI_OK) {
    return hr;
  }
  return open_fifo(fifo, riid, ppv);
}

}  // extern "C"