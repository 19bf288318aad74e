/*
 * sl64_types.h - data types and constants of the SORCUS SL-CANi (S-Link type 64) driver task
 * SL64TASK and its library SL64_LIB (canemu).
 *
 * This project's own declarations of the names the SORCUS manual "S-Link SL-CANi (Typ 64)" uses
 * (../shared/spec/sorcus-digest.md §1, §3.2, §3.4, §3.5). The manual gives the names, the
 * structure members and the diagnosis codes, but no numeric values for the flags (digest §7
 * point 1): every flag value below is canemu's, defined once here for the firmware model, the
 * daemon and the client library; the diagnosis codes, the return value 42h, function 14 and the
 * EEPROM layout are the manual's. docs/sorcus.md lists them all.
 *
 * Valid C11 and C++; includes only the C library.
 */
#ifndef CANEMU_SORCUS_SL64_TYPES_H
#define CANEMU_SORCUS_SL64_TYPES_H

#include <stdint.h>

#ifndef CANEMU_SORCUS_BASIC_TYPES
#define CANEMU_SORCUS_BASIC_TYPES
typedef uint8_t UCHAR;
typedef uint16_t USHORT;
typedef uint32_t ULONG;
#endif

/* The handle sl064_config_msg_object gives; 0 is never a handle («bei einem Fehler auf 0»). */
typedef USHORT SL064Handle;

/* sl064_config_msg_object's configuration. */
typedef struct {
  ULONG id;             /* 0..2031 (11 bit) or 0..268435447 (29 bit), as documented */
  USHORT control_flags; /* _SL064_* below */
  USHORT serv_task;     /* message service routine: task number */
  USHORT serv_func;     /*                          function number */
} SL064MsgType;

/* control_flags (values canemu's). */
#define _SL064_SEND 0x0001        /* a send object (else a receive object) */
#define _SL064_ACTIVE 0x0002      /* sends / requests on the application's call */
#define _SL064_PASSIVE 0x0004     /* answers remote frames / waits for data */
#define _SL064_EXCL_BUFFER 0x0008 /* one of buffers 1..13 for this object alone (max. 13) */
#define _SL064_DISABLE_INT 0x0010 /* no interrupt when it sends; always active and passive */

/* The slots: micro_slot 0..5 = channels A..F. */
#define SL064_SLOTS 6

/* Identifier ranges as the manual prints them (digest §1.2, §7 point 4). */
#define SL064_MAX_ID_11 2031ul
#define SL064_MAX_ID_29 268435447ul

/* Function 14 of SL64TASK: the buffered service request to the PC (sl064_evaluate_srq). */
#define SL064_SRQ_SERVICE_FUNC 14
/* The service request word: low byte 80h, high byte the slot. */
#define SL064_SRQ_WORD(slot) ((USHORT)(0x0080u | ((unsigned)(slot) << 8)))

/* The return value of every function when the driver signals an error (PC program). Warnings
 * return 0. */
#define SL064_E_DRIVER 0x42
/* ... and in an on-card real-time program (not used by canemu's library). */
#define SL064_E_DRIVER_RT 0x42E0

/* Diagnosis codes (sl064_get_diagnosis; the manual's values). Below 21h: warnings. */
#define SL064_DIAG_OK 0x00
#define SL064_DIAG_SIZE_MISMATCH 0x01  /* received bytes differ from those requested */
#define SL064_DIAG_NO_ROUTINE 0x02     /* the service routine is not installed yet */
#define SL064_DIAG_NOT_SENT 0x03       /* the last send request is not yet on the bus */
#define SL064_DIAG_NOT_HANDLED 0x04    /* a frame came, its interrupt is not yet handled */
#define SL064_DIAG_LOST 0x05           /* a received message was lost */
#define SL064_DIAG_QUEUED 0x06         /* queued in the FIFO, not sent at once */
#define SL064_DIAG_NO_MEMORY 0x21      /* no memory for another message object */
#define SL064_DIAG_NO_RESPONSE 0x22    /* the S-Link does not respond */
#define SL064_DIAG_EEPROM_RANGE 0x24   /* an EEPROM parameter is out of range */
#define SL064_DIAG_EXCL_LIMIT 0x27     /* more than 13 objects with _SL064_EXCL_BUFFER */
#define SL064_DIAG_DUPLICATE_ID 0x28   /* an object with this ID exists */
#define SL064_DIAG_MASK_EXCLUDES 0x29  /* the mask would lock out configured messages */
#define SL064_DIAG_WRONG_HANDLE 0x2A   /* invalid handle, or an object of the wrong type */
#define SL064_DIAG_FIFO_FULL 0x2B      /* the FIFO is full */
#define SL064_DIAG_BUFFER15_MIXED 0x2C /* passive send and receive objects without EXCL */
#define SL064_DIAG_CALL_ORDER 0x2D     /* the configuration order was not followed */
#define SL064_DIAG_RESET_FAILED 0x2E   /* error resetting the S-Link */
#define SL064_DIAG_ASYNC_INIT 0x2F     /* error in the asynchronous initialisation */
#define SL064_DIAG_SYNC_INIT 0x30      /* error in the synchronous initialisation */
#define SL064_DIAG_EEPROM_CLOCK 0x31   /* EEPROM word 12 holds an invalid value */
#define SL064_DIAG_NO_M6P0500 0x32     /* M6P0500.LIB not installed correctly */
#define SL064_DIAG_M6P0500_ERROR 0x33  /* M6P0500.LIB reported an error */
#define SL064_DIAG_SCC_FREQUENCY 0x35  /* the SCC frequency must be 7.37 or 16.5 MHz */
#define SL064_DIAG_FIRST_ERROR 0x21

/* Error service routine status (and sl064_evaluate_srq's return value). */
#define SL064_STATUS_HEAVY 1   /* 'Stark gestörter Bus' */
#define SL064_STATUS_BUS_OFF 2 /* 'Bus Off' */

/* The S-Link's EEPROM: 64 words; of words 0..31 only 13..19 may be changed, 32..63 are free. */
#define SL064_EEPROM_WORDS 64
#define SL064_EEPROM_CLOCK 12           /* 0010h = 10 MHz; must not be changed */
#define SL064_EEPROM_MODE 13            /* bits 0..2 always 1; bit 3 termination */
#define SL064_EEPROM_ID_FORMAT 14       /* bit 0: 0 = 11 bit, 1 = 29 bit */
#define SL064_EEPROM_TQ 15              /* t_Q in ns, 100..6400 */
#define SL064_EEPROM_TSEG1 16           /* 3..16 */
#define SL064_EEPROM_TSEG2 17           /* 2..8 */
#define SL064_EEPROM_SJW 18             /* 1..4 */
#define SL064_EEPROM_SAMPLES 19         /* 1 or 3 */
#define SL064_EEPROM_TERMINATION 0x0008 /* word 13 bit 3 */

#endif /* CANEMU_SORCUS_SL64_TYPES_H */
