/*
 * Event objects for VCI programs on Linux: the subset of the Windows event API the VCI C++
 * examples use (CreateEvent, SetEvent, ResetEvent, WaitForSingleObject,
 * WaitForMultipleObjects, CloseHandle), over eventfds. An event HANDLE from CreateEvent is what
 * IFifoReader/IFifoWriter::AssignEvent and IVciEnumDevice::AssignEvent take;
 * canemuEventFd() gives its descriptor for poll/epoll/select (readable while signalled).
 * Part of libvciapi.so.
 */
#ifndef CANEMU_EVENTS_H
#define CANEMU_EVENTS_H

#include "vcitype.h"

#ifdef __cplusplus
extern "C" {
#endif

#ifndef INFINITE
#define INFINITE 0xFFFFFFFFu
#endif
#ifndef WAIT_OBJECT_0
#define WAIT_OBJECT_0 0x00000000u
#endif
#ifndef WAIT_TIMEOUT
#define WAIT_TIMEOUT 0x00000102u
#endif
#ifndef WAIT_FAILED
#define WAIT_FAILED 0xFFFFFFFFu
#endif

/* An event, signalled or not; a manual-reset event stays signalled until ResetEvent, an
 * auto-reset one is reset by the wait it ends. Attributes and name are ignored. NULL when no
 * descriptor is left. */
HANDLE VCIAPI CreateEvent(PVOID pAttributes, BOOL bManualReset, BOOL bInitialState,
                          const char* pszName);
BOOL VCIAPI SetEvent(HANDLE hEvent);
BOOL VCIAPI ResetEvent(HANDLE hEvent);
/* WAIT_OBJECT_0 when signalled within dwMilliseconds (INFINITE: no limit), WAIT_TIMEOUT,
 * WAIT_FAILED for a handle that is not an event. */
UINT32 VCIAPI WaitForSingleObject(HANDLE hEvent, UINT32 dwMilliseconds);
/* WAIT_OBJECT_0 + i for the first signalled event i (bWaitAll FALSE), or WAIT_OBJECT_0 when
 * all are (bWaitAll TRUE). */
UINT32 VCIAPI WaitForMultipleObjects(UINT32 nCount, const HANDLE* pHandles, BOOL bWaitAll,
                                     UINT32 dwMilliseconds);
BOOL VCIAPI CloseHandle(HANDLE hObject);
/* The event's descriptor (readable while signalled), -1 for a handle that is not an event. */
int VCIAPI canemuEventFd(HANDLE hEvent);

#ifdef __cplusplus
}
#endif

#endif /* CANEMU_EVENTS_H */
