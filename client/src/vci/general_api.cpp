// The functions of the VCI C API that do not depend on the bus (vcinpl_general.h), the same in
// libvcinpl and libvcinpl2: error texts, identifiers as text, event objects.
#include <algorithm>
#include <cstdio>
#include <optional>
#include <string>

#include <unistd.h>

#include "events.hpp"
#include "vci_core.hpp"
#include "vcinpl_general.h"

using namespace canemu::client::vci;

namespace {

// Writes as much of `text` as fits in `size` characters with the NUL.
template <class Char, class Text>
void truncate_into(const Text& text, Char* out, UINT32 size) {
  if (out == nullptr || size == 0) {
    return;
  }
  const std::size_t n = std::min<std::size_t>(text.size(), size - 1);
  for (std::size_t i = 0; i < n; ++i) {
    out[i] = static_cast<Char>(text[i]);
  }
  out[n] = Char{};
}

void display(const std::string& caption, bool has_caption, HRESULT hr) {
  const std::string line = (has_caption ? caption + ": " : "") + format_error(hr) + "\n";
  std::fflush(stderr);  // after anything the program wrote there through stdio
  [[maybe_unused]] const ssize_t n = ::write(STDERR_FILENO, line.data(), line.size());
}

template <class Char>
HRESULT to_luid(const Char* text, PVCIID out, std::optional<std::string> narrow_text) {
  if (text == nullptr || out == nullptr) {
    return VCI_E_INVALIDARG;
  }
  const auto id = narrow_text ? parse_luid(*narrow_text) : std::nullopt;
  if (!id) {
    return VCI_E_FAIL;
  }
  *out = *id;
  return VCI_OK;
}

template <class Char>
HRESULT to_guid(const Char* text, PGUID out, std::optional<std::string> narrow_text) {
  if (text == nullptr || out == nullptr) {
    return VCI_E_INVALIDARG;
  }
  const auto g = narrow_text ? parse_guid(*narrow_text) : std::nullopt;
  if (!g) {
    return VCI_E_FAIL;
  }
  *out = *g;
  return VCI_OK;
}

std::optional<std::string> ascii_of(const wchar_t* text) {
  return text == nullptr ? std::nullopt : narrow_ascii(text);
}
std::optional<std::string> ascii_of(const char* text) {
  return text == nullptr ? std::nullopt : std::optional<std::string>(text);
}

}  // namespace

extern "C" {

// ---- error texts ----

void VCIAPI vciFormatErrorA(HRESULT hrError, PCHAR pszText, UINT32 dwLength) {
  truncate_into(format_error(hrError), pszText, dwLength);
}

void VCIAPI vciFormatError(HRESULT hrError, PCHAR pszText, UINT32 dwLength) {
  vciFormatErrorA(hrError, pszText, dwLength);
}

void VCIAPI vciFormatErrorW(HRESULT hrError, PWCHAR pwszText, UINT32 dwLength) {
  truncate_into(widen(format_error(hrError)), pwszText, dwLength);
}

void VCIAPI vciDisplayErrorA(HWND, PCHAR pszCaption, HRESULT hrError) {
  display(pszCaption != nullptr ? pszCaption : "", pszCaption != nullptr, hrError);
}

void VCIAPI vciDisplayError(HWND hwndParent, PCHAR pszCaption, HRESULT hrError) {
  vciDisplayErrorA(hwndParent, pszCaption, hrError);
}

void VCIAPI vciDisplayErrorW(HWND, PWCHAR pwszCaption, HRESULT hrError) {
  display(pwszCaption != nullptr ? narrow(pwszCaption) : "", pwszCaption != nullptr, hrError);
}

// ---- identifiers ----

HRESULT VCIAPI vciCreateLuid(PVCIID pVciid) {
  if (pVciid == nullptr) {
    return VCI_E_INVALIDARG;
  }
  pVciid->AsInt64 = new_luid();
  return VCI_OK;
}

HRESULT VCIAPI vciLuidToCharA(REFVCIID rVciid, PCHAR pszLuid, LONG cbSize) {
  return copy_text(luid_text(rVciid), pszLuid, cbSize);
}

HRESULT VCIAPI vciLuidToChar(REFVCIID rVciid, PCHAR pszLuid, LONG cbSize) {
  return vciLuidToCharA(rVciid, pszLuid, cbSize);
}

HRESULT VCIAPI vciLuidToCharW(REFVCIID rVciid, PWCHAR pwszLuid, LONG cbSize) {
  return copy_text(luid_text(rVciid), pwszLuid, cbSize);
}

HRESULT VCIAPI vciCharToLuidA(PCHAR pszLuid, PVCIID pVciid) {
  return to_luid(pszLuid, pVciid, ascii_of(pszLuid));
}

HRESULT VCIAPI vciCharToLuid(PCHAR pszLuid, PVCIID pVciid) {
  return vciCharToLuidA(pszLuid, pVciid);
}

HRESULT VCIAPI vciCharToLuidW(PWCHAR pwszLuid, PVCIID pVciid) {
  return to_luid(pwszLuid, pVciid, ascii_of(pwszLuid));
}

HRESULT VCIAPI vciGuidToCharA(REFGUID rGuid, PCHAR pszGuid, LONG cbSize) {
  return copy_text(guid_text(rGuid), pszGuid, cbSize);
}

HRESULT VCIAPI vciGuidToChar(REFGUID rGuid, PCHAR pszGuid, LONG cbSize) {
  return vciGuidToCharA(rGuid, pszGuid, cbSize);
}

HRESULT VCIAPI vciGuidToCharW(REFGUID rGuid, PWCHAR pwszGuid, LONG cbSize) {
  return copy_text(guid_text(rGuid), pwszGuid, cbSize);
}

HRESULT VCIAPI vciCharToGuidA(PCHAR pszGuid, PGUID pGuid) {
  return to_guid(pszGuid, pGuid, ascii_of(pszGuid));
}

HRESULT VCIAPI vciCharToGuid(PCHAR pszGuid, PGUID pGuid) {
  return vciCharToGuidA(pszGuid, pGuid);
}

HRESULT VCIAPI vciCharToGuidW(PWCHAR pwszGuid, PGUID pGuid) {
  return to_guid(pwszGuid, pGuid, ascii_of(pwszGuid));
}

// ---- events ----

HRESULT VCIAPI vciEventCreate(BOOL fManReset, BOOL fInitState, PHANDLE phEvent) {
  if (phEvent == nullptr) {
    return VCI_E_INVALIDARG;
  }
  *phEvent = create_event(fManReset != 0, fInitState != 0);
  return *phEvent != nullptr ? VCI_OK : VCI_E_OUTOFMEMORY;
}

HRESULT VCIAPI vciEventDelete(HANDLE hEvent) {
  return unregister_object(hEvent, Object::Kind::event) ? VCI_OK : VCI_E_INVHANDLE;
}

HRESULT VCIAPI vciEventSignal(HANDLE hEvent) {
  EventObj* e = event_of(hEvent);
  if (e == nullptr) {
    return VCI_E_INVHANDLE;
  }
  e->set();
  return VCI_OK;
}

HRESULT VCIAPI vciEventReset(HANDLE hEvent) {
  EventObj* e = event_of(hEvent);
  if (e == nullptr) {
    return VCI_E_INVHANDLE;
  }
  e->reset();
  return VCI_OK;
}

HRESULT VCIAPI vciEventWaitFor(HANDLE hEvent, UINT32 dwTimeout) {
  EventObj* e = event_of(hEvent);
  if (e == nullptr) {
    return VCI_E_INVHANDLE;
  }
  return wait_events({e}, false, dwTimeout) == 0 ? VCI_OK : VCI_E_TIMEOUT;
}

}  // extern "C"
