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

// The interface and class identifiers of IXXAT's VCI 4 SDK (vcisdk.h), so that a program that
// compares or stores them sees the vendor's values. docs/vci.md.
extern "C" {
const IID IID_IUnknown = {0x00000000U, 0x0000, 0x0000, {0xC0, 0, 0, 0, 0, 0, 0, 0x46}};
const IID IID_IVciDeviceManager = {
    0x7724B0A9U, 0xE6DB, 0x46B0, {0xA5, 0xD0, 0x46, 0x8C, 0xC4, 0x19, 0x17, 0x32}};
const IID IID_IVciEnumDevice = {
    0x1AD18613U, 0xCC67, 0x4AC8, {0x83, 0xFA, 0x6A, 0xD2, 0x4B, 0xDE, 0x62, 0x9A}};
const IID IID_IVciDevice = {
    0x46DFCF2FU, 0x113B, 0x4D01, {0xA8, 0x03, 0xBD, 0x5B, 0x4D, 0x32, 0xC8, 0xF1}};
const IID IID_IBalObject = {
    0xA2B958AAU, 0x9188, 0x4CDB, {0x83, 0x07, 0x25, 0xD9, 0xF1, 0xF8, 0x43, 0xE9}};
const IID IID_ICanSocket = {
    0x48965C25U, 0x9F8D, 0x4E4D, {0x8D, 0xE6, 0xF0, 0x29, 0x80, 0x8C, 0x9E, 0xD2}};
const IID IID_ICanSocket2 = {
    0xD914F5A7U, 0x12FA, 0x41F6, {0x8A, 0xB4, 0x4E, 0xA8, 0x9F, 0x1C, 0x5F, 0x1E}};
const IID IID_ICanControl = {
    0xD213C143U, 0x7039, 0x4D1D, {0xAC, 0xED, 0x13, 0x90, 0x28, 0x9C, 0x8E, 0xBA}};
const IID IID_ICanControl2 = {
    0xEFD3A8E2U, 0x09E3, 0x4115, {0x86, 0x9F, 0x93, 0xE5, 0x79, 0x16, 0x74, 0x31}};
const IID IID_ICanChannel = {
    0x66FF396BU, 0x22EA, 0x42AA, {0xBC, 0x7E, 0x49, 0x19, 0xF8, 0x9F, 0xB4, 0x5C}};
const IID IID_ICanChannel2 = {
    0xF2528F90U, 0x3A10, 0x46D0, {0x8F, 0x82, 0x08, 0x71, 0xC1, 0xE7, 0xDB, 0xB9}};
const IID IID_ICanScheduler = {
    0xC936498FU, 0xEC52, 0x4C74, {0xB3, 0xFE, 0xA4, 0x72, 0xBA, 0x73, 0x65, 0xBA}};
const IID IID_ICanScheduler2 = {
    0x70E3E8B8U, 0x852F, 0x48E0, {0xBD, 0xDB, 0xB1, 0x0A, 0x0C, 0x44, 0xCB, 0x3F}};
const IID IID_IFifoReader = {
    0x19286603U, 0xA9CD, 0x433A, {0xA4, 0x95, 0x72, 0xE5, 0xC9, 0xD9, 0x7A, 0x97}};
const IID IID_IFifoWriter = {
    0xE1CC08CEU, 0x99C0, 0x483B, {0x8E, 0x5F, 0x4C, 0x43, 0x35, 0x8E, 0x1C, 0xE2}};
const IID IID_IVciFifo = {
    0x25A79E68U, 0x912C, 0x41BF, {0x8C, 0xC7, 0xA7, 0x09, 0x67, 0x2F, 0xF1, 0x02}};
const IID IID_IVciFifo2 = {
    0x66E3AA3AU, 0x6BF6, 0x47A0, {0xAB, 0x18, 0xEF, 0xC8, 0x01, 0x09, 0x1E, 0x61}};
const IID IID_ILinSocket = {
    0xEF865638U, 0x6D07, 0x4A46, {0xA8, 0x38, 0x4B, 0xAF, 0xED, 0x35, 0x9B, 0x1A}};
const IID IID_ILinControl = {
    0x4D58EF55U, 0x4F01, 0x451E, {0x91, 0x1F, 0x17, 0xC2, 0x23, 0xA8, 0xB8, 0xF0}};
const IID IID_ILinMonitor = {
    0x29068E57U, 0x6B69, 0x4010, {0x91, 0x1C, 0x7A, 0x91, 0x28, 0x52, 0x1B, 0xE0}};
const CLSID CLSID_VCIBAL = {
    0x3CB880F4U, 0x2791, 0x40BD, {0xB8, 0x52, 0x09, 0x34, 0x9D, 0x1A, 0x7B, 0x37}};
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