/*
 * vcitype.h - base types of the VCI API (canemu).
 *
 * This project's own declarations, binary-compatible with the layouts of the IXXAT VCI SDK
 * (VCI V4). They give the Windows-style type names the SDK uses, the identifier types (LUID,
 * GUID, VCIID), the version, device and BAL information structures, and the bus/controller
 * type word helpers. Shared by the firmware model, the daemon and the client libraries; valid
 * C11 and C++. Reference: the IXXAT "VCI: C++ Software Design Guide" sections 8.1 and 8.2
 * (device and BAL structures).
 *
 * Packing: every structure is byte-packed (pack 1); VCIID uses pack 8, as the SDK does.
 */
#ifndef CANEMU_VCI_VCITYPE_H
#define CANEMU_VCI_VCITYPE_H

#include <stddef.h> /* wchar_t in C */
#include <stdint.h>

/* ------------------------------------------------------------------------------------------
 * Calling convention and compile-time checks
 * ------------------------------------------------------------------------------------------ */

/* Calling convention of the exported VCI functions: the default one on Linux. */
#ifndef VCIAPI
#define VCIAPI
#endif

/* VCI_STATIC_ASSERT(cond, msg): a compile-time check at file scope, in C11 and in C++. */
#if defined(__cplusplus)
#define VCI_STATIC_ASSERT(cond, msg) static_assert(cond, msg)
#elif defined(__STDC_VERSION__) && (__STDC_VERSION__ >= 201112L)
#define VCI_STATIC_ASSERT(cond, msg) _Static_assert(cond, msg)
#else /* before C11: a negative array size fails; repeating this declaration is allowed */
#define VCI_STATIC_ASSERT(cond, msg) extern char vci_static_assert_[(cond) ? 1 : -1]
#endif

/* VCI_ASSERT_SIZE(type, size): the binary layout of `type` is `size` bytes. */
#define VCI_ASSERT_SIZE(type, size) \
  VCI_STATIC_ASSERT(sizeof(type) == (size), "sizeof(" #type ") must be " #size " bytes")

/* ------------------------------------------------------------------------------------------
 * Base types (Windows names)
 * ------------------------------------------------------------------------------------------ */

typedef uint8_t UINT8;
typedef int8_t INT8;
typedef uint16_t UINT16;
typedef int16_t INT16;
typedef uint32_t UINT32;
typedef int32_t INT32;
typedef uint64_t UINT64;
typedef int64_t INT64;

typedef INT32 BOOL; /* 32-bit, as on Windows */
typedef UINT8 BOOL8;
typedef INT32 BOOL32;

typedef char CHAR;
typedef char TCHAR; /* no UNICODE build: TCHAR is always char */
/* The W (wide) functions take wchar_t text: 32-bit on Linux, what L"..." literals and the
 * wcs* functions use (on Windows WCHAR is 16-bit UTF-16). */
typedef wchar_t WCHAR;
typedef INT32 LONG; /* 32-bit, as on Windows (LLP64), not the 64-bit Linux long */
typedef UINT32 ULONG;
typedef float FLOAT;

typedef INT32 HRESULT; /* signed 32-bit: negative values are errors */
typedef void* HANDLE;
typedef void* PVOID;

typedef UINT8* PUINT8;
typedef INT8* PINT8;
typedef UINT16* PUINT16;
typedef INT16* PINT16;
typedef UINT32* PUINT32;
typedef INT32* PINT32;
typedef UINT64* PUINT64;
typedef INT64* PINT64;
typedef BOOL* PBOOL;
typedef BOOL8* PBOOL8;
typedef BOOL32* PBOOL32;
typedef CHAR* PCHAR;
typedef WCHAR* PWCHAR;
typedef TCHAR* PTCHAR;
typedef LONG* PLONG;
typedef ULONG* PULONG;
typedef FLOAT* PFLOAT;
typedef HRESULT* PHRESULT;
typedef HANDLE* PHANDLE;
typedef void* HWND; /* a window; the VCI functions that take one ignore it on Linux */

#ifndef TRUE
#define TRUE 1
#endif
#ifndef FALSE
#define FALSE 0
#endif

/* ------------------------------------------------------------------------------------------
 * LUID, GUID and VCIID
 * ------------------------------------------------------------------------------------------ */

/* LUID and GUID have no padding; they keep their natural (4-byte) alignment, as on Windows. */

/* Locally unique identifier (8 bytes). */
typedef struct _LUID {
  UINT32 LowPart;
  INT32 HighPart;
} LUID, *PLUID;

/* Globally unique identifier (16 bytes), laid out as on Windows. */
#ifndef GUID_DEFINED
#define GUID_DEFINED
typedef struct _GUID {
  UINT32 Data1;
  UINT16 Data2;
  UINT16 Data3;
  UINT8 Data4[8];
} GUID;
#endif
typedef GUID* PGUID;

#if defined(__cplusplus)
typedef const GUID& REFGUID;
typedef const GUID& REFIID;
typedef const GUID& REFCLSID;
#else
typedef const GUID* REFGUID;
typedef const GUID* REFIID;
typedef const GUID* REFCLSID;
#endif

#pragma pack(push, 8)

/* VCI object identifier: a LUID, also readable as one 64-bit integer (8 bytes). */
typedef union _VCIID {
  LUID AsLuid;
  INT64 AsInt64;
} VCIID, *PVCIID;

#pragma pack(pop)

#if defined(__cplusplus)
typedef const VCIID& REFVCIID;
#else
typedef const VCIID* REFVCIID;
#endif

/* ------------------------------------------------------------------------------------------
 * Bus and controller type words
 *
 * A 16-bit type word holds the bus type in the high byte and the controller type (for CAN one
 * of the CAN_CTRL_* values of cantype.h) in the low byte.
 * ------------------------------------------------------------------------------------------ */

#define VCI_MAX_BUSCTRL 32 /* maximum number of bus controllers of one device */

#define VCI_BUS_RES 0 /* reserved */
#define VCI_BUS_CAN 1 /* CAN */
#define VCI_BUS_LIN 2 /* LIN */
#define VCI_BUS_FLX 3 /* FlexRay */
#define VCI_BUS_KLN 4 /* K-Line */

/* Builds a type word from a bus type and a controller type. */
#define VCI_BUS_CTRL(bus, ctrl) ((UINT16)((((UINT16)(bus)&0xFFu) << 8) | ((UINT16)(ctrl)&0xFFu)))
/* Bus type (high byte) of a type word. */
#define VCI_BUS_TYPE(busctrl) ((UINT8)(((UINT16)(busctrl) >> 8) & 0xFFu))
/* Controller type (low byte) of a type word. */
#define VCI_CTL_TYPE(busctrl) ((UINT8)((UINT16)(busctrl)&0xFFu))

/* Type words of a controller of a given bus: VCI_CAN_CTRL(CAN_CTRL_SJA1000) etc. */
#define VCI_CAN_CTRL(ctrl) VCI_BUS_CTRL(VCI_BUS_CAN, ctrl)
#define VCI_LIN_CTRL(ctrl) VCI_BUS_CTRL(VCI_BUS_LIN, ctrl)
#define VCI_FLX_CTRL(ctrl) VCI_BUS_CTRL(VCI_BUS_FLX, ctrl)

/* Type words of the controllers (the CAN_CTRL_* values come from cantype.h, LIN_CTRL_* from
 * lintype.h). */
#define VCI_CAN_UNKNOWN VCI_CAN_CTRL(CAN_CTRL_UNKNOWN)
#define VCI_CAN_82527 VCI_CAN_CTRL(CAN_CTRL_82527)
#define VCI_CAN_82C200 VCI_CAN_CTRL(CAN_CTRL_82C200)
#define VCI_CAN_81C90 VCI_CAN_CTRL(CAN_CTRL_81C90)
#define VCI_CAN_82C90 VCI_CAN_81C90 /* older (misspelt) name */
#define VCI_CAN_81C92 VCI_CAN_CTRL(CAN_CTRL_81C92)
#define VCI_CAN_82C92 VCI_CAN_81C92 /* older (misspelt) name */
#define VCI_CAN_SJA1000 VCI_CAN_CTRL(CAN_CTRL_SJA1000)
#define VCI_CAN_82C900 VCI_CAN_CTRL(CAN_CTRL_82C900)
#define VCI_CAN_TOUCAN VCI_CAN_CTRL(CAN_CTRL_TOUCAN)
#define VCI_CAN_MSCAN VCI_CAN_CTRL(CAN_CTRL_MSCAN)
#define VCI_CAN_FLEXCAN VCI_CAN_CTRL(CAN_CTRL_FLEXCAN)
#define VCI_CAN_IFICAN VCI_CAN_CTRL(CAN_CTRL_IFICAN)
#define VCI_CAN_IFI VCI_CAN_IFICAN /* older name */
#define VCI_CAN_BCCAN VCI_CAN_CTRL(CAN_CTRL_BCCAN)
#define VCI_CAN_CCAN VCI_CAN_BCCAN /* older name */
#define VCI_CAN_BXCAN VCI_CAN_CTRL(CAN_CTRL_BXCAN)
#define VCI_CAN_IFICFD VCI_CAN_CTRL(CAN_CTRL_IFICFD)
#define VCI_CAN_BMCAN VCI_CAN_CTRL(CAN_CTRL_BMCAN)
#define VCI_LIN_UNKNOWN VCI_LIN_CTRL(LIN_CTRL_UNKNOWN)
#define VCI_FLX_UNKNOWN VCI_FLX_CTRL(0)
#define VCI_KLN_UNKNOWN VCI_BUS_CTRL(VCI_BUS_KLN, 0)

/* ------------------------------------------------------------------------------------------
 * Version, device and BAL information
 * ------------------------------------------------------------------------------------------ */

#pragma pack(push, 1)

/* VCI and operating-system version (VciGetVersion), 32 bytes. */
typedef struct _VCIVERSIONINFO {
  UINT32 VciMajorVersion;
  UINT32 VciMinorVersion;
  union {
    UINT32 VciRevNumber;     /* the SDK's name */
    UINT32 VciReleaseNumber; /* the C++ guide's name, same field */
  };
  UINT32 VciBuildNumber;
  UINT32 OsMajorVersion;
  UINT32 OsMinorVersion;
  UINT32 OsBuildNumber;
  UINT32 OsPlatformId;
} VCIVERSIONINFO, *PVCIVERSIONINFO;

/* Device information (IVciEnumDevice::Next, IVciDevice::GetDeviceInfo), 304 bytes. */
typedef struct _VCIDEVICEINFO {
  VCIID VciObjectId; /* runtime-unique object id, key of OpenDevice */
  GUID DeviceClass;  /* device class (driver/device kind) */
  UINT8 DriverMajorVersion;
  UINT8 DriverMinorVersion;
  UINT16 DriverBuildVersion;
  UINT8 HardwareBranchVersion;
  UINT8 HardwareMajorVersion;
  UINT8 HardwareMinorVersion;
  UINT8 HardwareBuildVersion;
  union {
    CHAR AsChar[16];      /* "HW..." Latin-1 serial number, */
    GUID AsGuid;          /* otherwise a GUID */
  } UniqueHardwareId;     /* persistent hardware id */
  CHAR Description[128];  /* NUL-terminated Latin-1 */
  CHAR Manufacturer[126]; /* NUL-terminated Latin-1 */
  UINT16 DriverReleaseVersion;
} VCIDEVICEINFO, *PVCIDEVICEINFO;

/* Device capabilities (IVciDevice::GetDeviceCaps), 66 bytes. */
typedef struct _VCIDEVICECAPS {
  UINT16 BusCtrlCount;                  /* number of bus controllers */
  UINT16 BusCtrlTypes[VCI_MAX_BUSCTRL]; /* type word per controller; [0] = bus 1 */
} VCIDEVICECAPS, *PVCIDEVICECAPS;

#define BAL_MAX_SOCKETS VCI_MAX_BUSCTRL /* maximum number of BAL bus sockets */

/* BAL features (IBalObject::GetFeatures), 70 bytes. */
typedef struct _BALFEATURES {
  UINT16 FwMajorVersion;
  UINT16 FwMinorVersion;
  UINT16 BusSocketCount;                 /* number of bus sockets */
  UINT16 BusSocketType[BAL_MAX_SOCKETS]; /* type word per socket */
} BALFEATURES, *PBALFEATURES;

/* Bus socket information (GetSocketInfo), 12 bytes. */
typedef struct _BALSOCKETINFO {
  VCIID Obid;   /* controller id, valid while the BAL object lives */
  UINT16 Type;  /* type word */
  UINT16 BusNo; /* 0 .. BusSocketCount - 1 */
} BALSOCKETINFO, *PBALSOCKETINFO;

#pragma pack(pop)

/* ------------------------------------------------------------------------------------------
 * Layout checks
 * ------------------------------------------------------------------------------------------ */

VCI_ASSERT_SIZE(UINT8, 1);
VCI_ASSERT_SIZE(UINT16, 2);
VCI_ASSERT_SIZE(UINT32, 4);
VCI_ASSERT_SIZE(UINT64, 8);
VCI_ASSERT_SIZE(BOOL, 4);
VCI_ASSERT_SIZE(BOOL8, 1);
VCI_ASSERT_SIZE(BOOL32, 4);
VCI_ASSERT_SIZE(LONG, 4);
VCI_ASSERT_SIZE(HRESULT, 4);
VCI_ASSERT_SIZE(LUID, 8);
VCI_ASSERT_SIZE(GUID, 16);
VCI_ASSERT_SIZE(VCIID, 8);
VCI_ASSERT_SIZE(VCIVERSIONINFO, 32);
VCI_ASSERT_SIZE(VCIDEVICEINFO, 304);
VCI_ASSERT_SIZE(VCIDEVICECAPS, 66);
VCI_ASSERT_SIZE(BALFEATURES, 70);
VCI_ASSERT_SIZE(BALSOCKETINFO, 12);

#endif /* CANEMU_VCI_VCITYPE_H */
