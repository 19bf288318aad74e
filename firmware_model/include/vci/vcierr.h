/*
 * vcierr.h - result codes of the VCI API (canemu).
 *
 * This project's own declarations, binary-compatible with the IXXAT VCI SDK (VCI V4): every
 * method returns an HRESULT; VCI_OK is success and each VCI_E_* error is 0xE0010000 | n
 * (severity "error" 0xC0000000, customer flag 0x20000000, facility VCI 0x0001).
 * Reference: the IXXAT "VCI: C++ Software Design Guide", the error codes of each method in section
 * 7; numeric values follow the vendor SDK (docs/vci.md).
 */
#ifndef CANEMU_VCI_VCIERR_H
#define CANEMU_VCI_VCIERR_H

#include "vcitype.h"

#define VCI_FACILITY 0x0001    /* facility code of the VCI */
#define VCI_E_BASE 0xE0010000u /* severity error | customer flag | facility VCI */

/* Builds the VCI error code number n (1 .. 0xFFFF). */
#define VCI_ERROR_CODE(n) ((HRESULT)(VCI_E_BASE | (UINT32)(n)))

/* Success / failure tests: errors are negative HRESULTs. */
#define VCI_SUCCEEDED(hr) ((HRESULT)(hr) >= 0)
#define VCI_FAILED(hr) ((HRESULT)(hr) < 0)

#define VCI_OK ((HRESULT)0x00000000) /* success */

#define VCI_E_UNEXPECTED VCI_ERROR_CODE(0x0001)            /* unexpected error */
#define VCI_E_NOT_IMPLEMENTED VCI_ERROR_CODE(0x0002)       /* not implemented / supported */
#define VCI_E_OUTOFMEMORY VCI_ERROR_CODE(0x0003)           /* out of memory or resources */
#define VCI_E_INVALIDARG VCI_ERROR_CODE(0x0004)            /* invalid argument */
#define VCI_E_NOINTERFACE VCI_ERROR_CODE(0x0005)           /* interface not supported */
#define VCI_E_INVPOINTER VCI_ERROR_CODE(0x0006)            /* invalid pointer */
#define VCI_E_INVHANDLE VCI_ERROR_CODE(0x0007)             /* invalid handle */
#define VCI_E_ABORT VCI_ERROR_CODE(0x0008)                 /* operation aborted */
#define VCI_E_FAIL VCI_ERROR_CODE(0x0009)                  /* unspecified failure */
#define VCI_E_ACCESSDENIED VCI_ERROR_CODE(0x000A)          /* access denied (object in use) */
#define VCI_E_TIMEOUT VCI_ERROR_CODE(0x000B)               /* timeout */
#define VCI_E_BUSY VCI_ERROR_CODE(0x000C)                  /* busy */
#define VCI_E_PENDING VCI_ERROR_CODE(0x000D)               /* pending */
#define VCI_E_NO_DATA VCI_ERROR_CODE(0x000E)               /* no data */
#define VCI_E_NO_MORE_ITEMS VCI_ERROR_CODE(0x000F)         /* end of a list */
#define VCI_E_NOT_INITIALIZED VCI_ERROR_CODE(0x0010)       /* not initialized */
#define VCI_E_ALREADY_INITIALIZED VCI_ERROR_CODE(0x0011)   /* already initialized */
#define VCI_E_RXQUEUE_EMPTY VCI_ERROR_CODE(0x0012)         /* receive FIFO empty */
#define VCI_E_TXQUEUE_FULL VCI_ERROR_CODE(0x0013)          /* transmit FIFO full */
#define VCI_E_BUFFER_OVERFLOW VCI_ERROR_CODE(0x0014)       /* buffer too small */
#define VCI_E_INVALID_STATE VCI_ERROR_CODE(0x0015)         /* not allowed in this state */
#define VCI_E_OBJECT_ALREADY_EXISTS VCI_ERROR_CODE(0x0016) /* object already exists */
#define VCI_E_INVALID_INDEX VCI_ERROR_CODE(0x0017)         /* invalid index */
#define VCI_E_END_OF_FILE VCI_ERROR_CODE(0x0018)           /* end of file */
#define VCI_E_DISCONNECTED VCI_ERROR_CODE(0x0019)          /* device disconnected */
#define VCI_E_WRONG_FLASHFWVERSION VCI_ERROR_CODE(0x001A)  /* wrong flash firmware version */

/* Alternative spelling of VCI_E_INVHANDLE (same code), used by this project's sources. */
#define VCI_E_INVALID_HANDLE VCI_E_INVHANDLE

#endif /* CANEMU_VCI_VCIERR_H */
