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
#define VCI_SUCCESS VCI_OK

#define VCI_E_UNEXPECTED VCI_ERROR_CODE(0x0001)             /* unexpected error */
#define VCI_E_NOT_IMPLEMENTED VCI_ERROR_CODE(0x0002)        /* not implemented / supported */
#define VCI_E_OUTOFMEMORY VCI_ERROR_CODE(0x0003)            /* out of memory or resources */
#define VCI_E_INVALIDARG VCI_ERROR_CODE(0x0004)             /* invalid argument */
#define VCI_E_NOINTERFACE VCI_ERROR_CODE(0x0005)            /* interface not supported */
#define VCI_E_INVPOINTER VCI_ERROR_CODE(0x0006)             /* invalid pointer */
#define VCI_E_INVHANDLE VCI_ERROR_CODE(0x0007)              /* invalid handle */
#define VCI_E_ABORT VCI_ERROR_CODE(0x0008)                  /* operation aborted */
#define VCI_E_FAIL VCI_ERROR_CODE(0x0009)                   /* unspecified failure */
#define VCI_E_ACCESSDENIED VCI_ERROR_CODE(0x000A)           /* access denied (object in use) */
#define VCI_E_TIMEOUT VCI_ERROR_CODE(0x000B)                /* timeout */
#define VCI_E_BUSY VCI_ERROR_CODE(0x000C)                   /* busy */
#define VCI_E_PENDING VCI_ERROR_CODE(0x000D)                /* pending */
#define VCI_E_NO_DATA VCI_ERROR_CODE(0x000E)                /* no data */
#define VCI_E_NO_MORE_ITEMS VCI_ERROR_CODE(0x000F)          /* end of a list */
#define VCI_E_NOT_INITIALIZED VCI_ERROR_CODE(0x0010)        /* not initialized */
#define VCI_E_ALREADY_INITIALIZED VCI_ERROR_CODE(0x0011)    /* already initialized */
#define VCI_E_RXQUEUE_EMPTY VCI_ERROR_CODE(0x0012)          /* receive FIFO empty */
#define VCI_E_TXQUEUE_FULL VCI_ERROR_CODE(0x0013)           /* transmit FIFO full */
#define VCI_E_BUFFER_OVERFLOW VCI_ERROR_CODE(0x0014)        /* buffer too small */
#define VCI_E_INVALID_STATE VCI_ERROR_CODE(0x0015)          /* not allowed in this state */
#define VCI_E_OBJECT_ALREADY_EXISTS VCI_ERROR_CODE(0x0016)  /* object already exists */
#define VCI_E_INVALID_INDEX VCI_ERROR_CODE(0x0017)          /* invalid index */
#define VCI_E_END_OF_FILE VCI_ERROR_CODE(0x0018)            /* end of file */
#define VCI_E_DISCONNECTED VCI_ERROR_CODE(0x0019)           /* device disconnected */
#define VCI_E_WRONG_FLASHFWVERSION VCI_ERROR_CODE(0x001A)   /* wrong flash firmware version */
#define VCI_E_INVALID_FIRMWARE VCI_E_WRONG_FLASHFWVERSION   /* the later name of 0x001A */
#define VCI_E_INVALID_LICENSE VCI_ERROR_CODE(0x001B)        /* invalid license */
#define VCI_E_NO_SUCH_LICENSE VCI_ERROR_CODE(0x001C)        /* no license */
#define VCI_E_LICENSE_EXPIRED VCI_ERROR_CODE(0x001D)        /* license expired */
#define VCI_E_LICENSE_QUOTA_EXCEEDED VCI_ERROR_CODE(0x001E) /* beyond the license's quota */
#define VCI_E_INVALID_TIMING VCI_ERROR_CODE(0x001F)         /* invalid bit timing */
#define VCI_E_IN_USE VCI_ERROR_CODE(0x0020)                 /* resource in use */
#define VCI_E_NO_SUCH_DEVICE VCI_ERROR_CODE(0x0021)         /* no such device */
#define VCI_E_DEVICE_NOT_CONNECTED VCI_ERROR_CODE(0x0022)   /* device not connected */
#define VCI_E_DEVICE_NOT_READY VCI_ERROR_CODE(0x0023)       /* device not ready */
#define VCI_E_TYPE_MISMATCH VCI_ERROR_CODE(0x0024)          /* wrong type of object */
#define VCI_E_NOT_SUPPORTED VCI_ERROR_CODE(0x0025)          /* request not supported */
#define VCI_E_DUPLICATE_OBJECTID VCI_ERROR_CODE(0x0026)     /* object id already indexed */
#define VCI_E_OBJECTID_NOT_FOUND VCI_ERROR_CODE(0x0027)     /* object id not found */
#define VCI_E_WRONG_LEVEL VCI_ERROR_CODE(0x0028)            /* called at the wrong level */
#define VCI_E_WRONG_DRV_VERSION VCI_ERROR_CODE(0x0029)      /* incompatible driver version */
#define VCI_E_LUIDS_EXHAUSTED VCI_ERROR_CODE(0x002A)        /* no LUID left */

/* ------------------------------------------------------------------------------------------
 * The parts of a result code, with the SDK's names: severity (bits 30-31), customer flag (29),
 * reserved flag (28), facility (16-27), code (0-15).
 * ------------------------------------------------------------------------------------------ */

#ifndef STATUS_SEVERITY_SUCCESS
#define STATUS_SEVERITY_SUCCESS 0
#endif
#ifndef STATUS_SEVERITY_INFORMATIONAL
#define STATUS_SEVERITY_INFORMATIONAL 1
#endif
#ifndef STATUS_SEVERITY_WARNING
#define STATUS_SEVERITY_WARNING 2
#endif
#ifndef STATUS_SEVERITY_ERROR
#define STATUS_SEVERITY_ERROR 3
#endif

#define SEV_SUCCESS STATUS_SEVERITY_SUCCESS
#define SEV_INFO STATUS_SEVERITY_INFORMATIONAL
#define SEV_WARN STATUS_SEVERITY_WARNING
#define SEV_ERROR STATUS_SEVERITY_ERROR

#define SCODE_MASK 0x0000FFFFu
#define FACILITY_MASK 0x0FFF0000u
#define RESERVED_FLAG 0x10000000u
#define SEVERITY_MASK 0xC0000000u
#define CUSTOMER_FLAG 0x20000000u
#define FACILITY_SHIFT 16
#define SEVERITY_SHIFT 30

#define MAKESCODE(c) ((UINT32)(c)&SCODE_MASK)
#define MAKEFACILITY(f) (((UINT32)(f) << FACILITY_SHIFT) & FACILITY_MASK)
#define MAKESEVERITY(s) (((UINT32)(s) << SEVERITY_SHIFT) & SEVERITY_MASK)
#define GETSCODE(e) ((UINT32)(e)&SCODE_MASK)
#define GETFACILITY(e) (((UINT32)(e)&FACILITY_MASK) >> FACILITY_SHIFT)
#define GETSEVERITY(e) (((UINT32)(e)&SEVERITY_MASK) >> SEVERITY_SHIFT)

#define FACILITY_VCI VCI_FACILITY
#define SEV_VCI_INFO (MAKESEVERITY(SEV_INFO) | CUSTOMER_FLAG | MAKEFACILITY(FACILITY_VCI))
#define SEV_VCI_WARN (MAKESEVERITY(SEV_WARN) | CUSTOMER_FLAG | MAKEFACILITY(FACILITY_VCI))
#define SEV_VCI_ERROR (MAKESEVERITY(SEV_ERROR) | CUSTOMER_FLAG | MAKEFACILITY(FACILITY_VCI))

/* A VCI code (customer flag and facility VCI), and codes of each severity. */
#define _IS_VCI_SCODE(e) ((((UINT32)(e)&CUSTOMER_FLAG) != 0) && (GETFACILITY(e) == FACILITY_VCI))
#define _VCI_INFO(c) ((HRESULT)(SEV_VCI_INFO | MAKESCODE(c)))
#define _VCI_WARN(c) ((HRESULT)(SEV_VCI_WARN | MAKESCODE(c)))
#define _VCI_ERROR(c) ((HRESULT)(SEV_VCI_ERROR | MAKESCODE(c)))

/* Alternative spelling of VCI_E_INVHANDLE (same code), used by this project's sources. */
#define VCI_E_INVALID_HANDLE VCI_E_INVHANDLE

#endif /* CANEMU_VCI_VCIERR_H */
