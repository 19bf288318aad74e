/*
 * sl64lib.h - the SORCUS SL-CANi library SL64_LIB (the sl064_* functions) as libsl64.so gives
 * it on canemud's emulated SL-CANi S-Links (canemu).
 *
 * The prototypes are the manual's ("Hochsprachenbibliothek"), the data types and constants are
 * in sl64_types.h (their values canemu's, docs/sorcus.md). Every USHORT function returns 0, or
 * 42h (SL064_E_DRIVER) when the driver signals an error; sl064_get_diagnosis tells which.
 *
 * The service routines of the manual are real-time functions on the card, named by task and
 * function number. Here they are functions of the program, installed by number with
 * canemu_sl064_install_message_service / _error_service; they run one after the other on one
 * thread of the library, in the order the emulation made the calls. Function 14 of SL64TASK
 * (SL064_SRQ_SERVICE_FUNC, task number canemu_sl064_driver_task(slot)) is the buffered service
 * request, read with sl064_evaluate_srq; canemu_sl064_wait_srq waits for one.
 *
 * A slot without an S-Link (none configured, or another program holds it) answers 42h with
 * diagnosis 22h («Das CAN-S-Link antwortet nicht»), as does every slot when canemud cannot be
 * reached. Functions may be called from any thread.
 */
#ifndef CANEMU_SORCUS_SL64LIB_H
#define CANEMU_SORCUS_SL64LIB_H

#include "sl64_types.h"

#ifdef __cplusplus
extern "C" {
#endif

#ifndef SL64API
#define SL64API
#endif

SL64API USHORT sl064_bib_startup(void);
SL64API USHORT sl064_config_module(UCHAR micro_slot, USHORT err_task, USHORT err_func);
SL64API USHORT sl064_config_msg_object(UCHAR micro_slot, SL064Handle* handle, SL064MsgType* config);
SL64API USHORT sl064_clear_configuration(UCHAR micro_slot);
SL64API USHORT sl064_start_com(UCHAR micro_slot);
SL64API USHORT sl064_stop_com(UCHAR micro_slot);
SL64API USHORT sl064_get_diagnosis(UCHAR micro_slot);
SL64API USHORT sl064_set_data(UCHAR micro_slot, SL064Handle handle, UCHAR* data, UCHAR size);
SL64API USHORT sl064_get_data(UCHAR micro_slot, SL064Handle handle, UCHAR* data_var,
                              UCHAR* size_var);
/* The manual prints "(UCHAR micro_slot; SL064Handle handle)". */
SL64API USHORT sl064_send_data(UCHAR micro_slot, SL064Handle handle);
SL64API USHORT sl064_send_data_request(UCHAR micro_slot, SL064Handle handle);
SL64API USHORT sl064_clear_msg(UCHAR micro_slot, SL064Handle handle);
SL64API USHORT sl064_set_acceptance_mask(UCHAR micro_slot, ULONG* mask, USHORT usage,
                                         USHORT serv_task, USHORT serv_func);
SL64API USHORT sl064_get_id(UCHAR micro_slot, SL064Handle handle, ULONG* id_var);
SL64API USHORT sl064_get_msg_count(UCHAR micro_slot, SL064Handle handle, ULONG* count);
SL64API void sl064_set_led(UCHAR micro_slot, UCHAR data);
/* The LED's state: the C name the manual prints, and its Pascal name. */
SL64API UCHAR sl064_get_dout(UCHAR micro_slot);
SL64API UCHAR sl064_get_led(UCHAR micro_slot);
SL64API USHORT sl064_evaluate_srq(UCHAR* micro_slot, SL064Handle* handle);
SL64API void sl064_enable_int_mask(UCHAR micro_slot);
SL64API void sl064_end_of_srq(UCHAR micro_slot);

/* canemu: the service routines, with the manual's parameters. */
typedef void (*SL064MessageService)(USHORT task, USHORT insize, SL064Handle* handle, USHORT outsize,
                                    ULONG* outdata);
typedef void (*SL064ErrorService)(USHORT task, USHORT insize, ULONG* status, USHORT outsize,
                                  UCHAR* outdata);
/* canemu: installs (NULL: removes) the routine with this task and function number; 0, or 42h
 * when the number is 0/0 or function 14 of a driver task. Before or after sl064_bib_startup. */
SL64API USHORT canemu_sl064_install_message_service(USHORT task, USHORT func,
                                                    SL064MessageService routine);
SL64API USHORT canemu_sl064_install_error_service(USHORT task, USHORT func,
                                                  SL064ErrorService routine);
/* canemu: SL64TASK's task number for a slot (40h + slot). */
SL64API USHORT canemu_sl064_driver_task(UCHAR micro_slot);
/* canemu: waits up to `timeout_ms` (-1: for ever) for a service request of function 14; its
 * word (80h | slot << 8), or 0 when none came. */
SL64API USHORT canemu_sl064_wait_srq(int timeout_ms);
/* canemu: routine calls for this slot dropped because 65536 calls were already waiting for the
 * routine thread (a routine slower than the bus), since the last canemu_sl064_connect. */
SL64API ULONG canemu_sl064_lost_calls(UCHAR micro_slot);
/* canemu: the S-Link's EEPROM (64 words). Writing: words 13..19 and 32..63; the word persists
 * in canemud's state file. 0, or 42h (read-only word, no such slot). */
SL64API USHORT canemu_sl064_eeprom_read(UCHAR micro_slot, USHORT word, USHORT* value);
SL64API USHORT canemu_sl064_eeprom_write(UCHAR micro_slot, USHORT word, USHORT value);
/* canemu: talk to the canemud at `socket` (NULL: CANEMU_SOCKET, then the usual places) from
 * now on; the slots held are given back. 0 once connected (NULL: always), else 42h. */
SL64API USHORT canemu_sl064_connect(const char* socket);

#ifdef __cplusplus
}
#endif

#endif /* CANEMU_SORCUS_SL64LIB_H */
