/*
 * vcinpl_general.h - the functions of the VCI C API that do not depend on the bus: error
 * texts, identifiers as text, event objects. The same in libvcinpl.so and libvcinpl2.so;
 * vcinpl.h and vcinpl2.h include it (the vendor's two headers declare these alike).
 *
 * A and W forms: the A functions take char text, the W functions wchar_t text (WCHAR is
 * wchar_t, 32-bit on Linux, the type of L"..." literals). Sizes of W buffers count
 * characters, not bytes. The plain names (vciFormatError, vciLuidToChar, ...) are the A forms,
 * exported under that name too for programs built against older headers and for lookups by
 * name (python-can asks for vciFormatError); with UNICODE defined they are macros for the W
 * forms, as in the vendor's headers.
 *
 * Text formats: a LUID (VCIID) is 16 upper-case hex digits of its 64-bit value (a buffer of at
 * least 17 characters with the NUL); a GUID is {XXXXXXXX-XXXX-XXXX-XXXX-XXXXXXXXXXXX} (at
 * least 39 characters). The vciCharTo* functions accept either case and nothing else.
 */
#ifndef CANEMU_VCI_VCINPL_GENERAL_H
#define CANEMU_VCI_VCINPL_GENERAL_H

#include "vcierr.h"
#include "vcitype.h"

#ifndef VCIAPI
#define VCIAPI
#endif

#ifndef VCI_MAX_ERRSTRLEN
#define VCI_MAX_ERRSTRLEN 256 /* buffer size that always holds a vciFormatError text */
#endif

#ifndef INFINITE
#define INFINITE 0xFFFFFFFFu /* a timeout without limit (a Windows name) */
#endif

#ifdef __cplusplus
extern "C" {
#endif

/* ---- error texts --------------------------------------------------------------------- */

/* Writes the text for hrError into pszText (at most dwLength characters with the NUL,
 * truncated to fit, always NUL-terminated when dwLength > 0); returns nothing. */
void VCIAPI vciFormatErrorA(HRESULT hrError, PCHAR pszText, UINT32 dwLength);
void VCIAPI vciFormatErrorW(HRESULT hrError, PWCHAR pwszText, UINT32 dwLength);

/* Shows the text for hrError: there is no message box on Linux, so it writes one line,
 * "<caption>: <text>" (just the text when pszCaption is NULL), to standard error.
 * hwndParent is ignored. */
void VCIAPI vciDisplayErrorA(HWND hwndParent, PCHAR pszCaption, HRESULT hrError);
void VCIAPI vciDisplayErrorW(HWND hwndParent, PWCHAR pwszCaption, HRESULT hrError);

/* ---- identifiers --------------------------------------------------------------------- */

/* Stores a new locally unique identifier in *pVciid; VCI_OK, VCI_E_INVALIDARG for NULL. */
HRESULT VCIAPI vciCreateLuid(PVCIID pVciid);

/* Writes rVciid as text; VCI_OK, VCI_E_INVALIDARG for a NULL buffer or cbSize <= 0,
 * VCI_E_BUFFER_OVERFLOW (nothing written) when cbSize < 17. */
HRESULT VCIAPI vciLuidToCharA(REFVCIID rVciid, PCHAR pszLuid, LONG cbSize);
HRESULT VCIAPI vciLuidToCharW(REFVCIID rVciid, PWCHAR pwszLuid, LONG cbSize);

/* Reads a LUID written by vciLuidToChar; VCI_OK, VCI_E_INVALIDARG for NULL pointers,
 * VCI_E_FAIL for text that is not one. */
HRESULT VCIAPI vciCharToLuidA(PCHAR pszLuid, PVCIID pVciid);
HRESULT VCIAPI vciCharToLuidW(PWCHAR pwszLuid, PVCIID pVciid);

/* Writes rGuid as text; VCI_OK, VCI_E_INVALIDARG, VCI_E_BUFFER_OVERFLOW when cbSize < 39. */
HRESULT VCIAPI vciGuidToCharA(REFGUID rGuid, PCHAR pszGuid, LONG cbSize);
HRESULT VCIAPI vciGuidToCharW(REFGUID rGuid, PWCHAR pwszGuid, LONG cbSize);

/* Reads a GUID in the form above; VCI_OK, VCI_E_INVALIDARG, VCI_E_FAIL. */
HRESULT VCIAPI vciCharToGuidA(PCHAR pszGuid, PGUID pGuid);
HRESULT VCIAPI vciCharToGuidW(PWCHAR pwszGuid, PGUID pGuid);

#ifdef UNICODE
#define vciFormatError vciFormatErrorW
#define vciDisplayError vciDisplayErrorW
#define vciLuidToChar vciLuidToCharW
#define vciCharToLuid vciCharToLuidW
#define vciGuidToChar vciGuidToCharW
#define vciCharToGuid vciCharToGuidW
#else
/* The A forms under their plain names (exported as such). */
void VCIAPI vciFormatError(HRESULT hrError, PCHAR pszText, UINT32 dwLength);
void VCIAPI vciDisplayError(HWND hwndParent, PCHAR pszCaption, HRESULT hrError);
HRESULT VCIAPI vciLuidToChar(REFVCIID rVciid, PCHAR pszLuid, LONG cbSize);
HRESULT VCIAPI vciCharToLuid(PCHAR pszLuid, PVCIID pVciid);
HRESULT VCIAPI vciGuidToChar(REFGUID rGuid, PCHAR pszGuid, LONG cbSize);
HRESULT VCIAPI vciCharToGuid(PCHAR pszGuid, PGUID pGuid);
#endif

/* ---- events -------------------------------------------------------------------------- */

/* Creates an event, signalled if fInitState; a manual-reset one (fManReset TRUE) stays
 * signalled until vciEventReset, an auto-reset one is reset by the vciEventWaitFor it ends.
 * Its handle goes to *phEvent; VCI_OK, VCI_E_INVALIDARG for NULL, VCI_E_OUTOFMEMORY when no
 * descriptor is left. */
HRESULT VCIAPI vciEventCreate(BOOL fManReset, BOOL fInitState, PHANDLE phEvent);

/* Destroys an event; VCI_OK, VCI_E_INVHANDLE. */
HRESULT VCIAPI vciEventDelete(HANDLE hEvent);

/* Signals an event (waking its waiters); VCI_OK, VCI_E_INVHANDLE. */
HRESULT VCIAPI vciEventSignal(HANDLE hEvent);

/* Resets an event to not signalled; VCI_OK, VCI_E_INVHANDLE. */
HRESULT VCIAPI vciEventReset(HANDLE hEvent);

/* Waits up to dwTimeout ms (0: test only, INFINITE: no limit) until the event is signalled;
 * VCI_OK when it is (an auto-reset event is reset), VCI_E_TIMEOUT, VCI_E_INVHANDLE. */
HRESULT VCIAPI vciEventWaitFor(HANDLE hEvent, UINT32 dwTimeout);

#ifdef __cplusplus
} /* extern "C" */
#endif

#endif /* CANEMU_VCI_VCINPL_GENERAL_H */
