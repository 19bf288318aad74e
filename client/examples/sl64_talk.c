/*
 * sl64_talk: two SL-CANi S-Links on one canemu bus, programmed the way the SORCUS manual's code
 * does it ("Hochsprachenbibliothek"): sl064_bib_startup, sl064_config_module,
 * sl064_config_msg_object with the manual's example object (ID 7, send active and passive,
 * service routine task 100 function 4), sl064_start_com, then set_data / send_data.
 *
 *   sl64_talk [SEND_SLOT [RECEIVE_SLOT [COUNT]]]      (defaults: 1 2 3)
 *
 * The S-Link in SEND_SLOT sends COUNT data frames with ID 7; the one in RECEIVE_SLOT receives
 * them with a passive receive object. Each frame is reported by the message service routine of
 * both sides (sent after the acknowledgement, received) and then read with sl064_get_data. Both
 * S-Links' EEPROMs are set to 500 kbit/s first (canemu's EEPROM access; on a Multi-COM card the
 * configuration tools do it). Built with
 *   cc sl64_talk.c $(pkg-config --cflags --libs canemu-sl64)
 */
#define _POSIX_C_SOURCE 200809L /* clock_gettime, also with -std=c11 */
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "sl64lib.h"

static pthread_mutex_t g_lock = PTHREAD_MUTEX_INITIALIZER;
static pthread_cond_t g_changed = PTHREAD_COND_INITIALIZER;
static unsigned g_events = 0;

/* The message service routine (task 100, function 4): only the handle carries meaning. */
static void message_service(USHORT task, USHORT insize, SL064Handle* handle, USHORT outsize,
                            ULONG* outdata) {
  (void)insize;
  (void)outsize;
  (void)outdata;
  printf("service routine %u/4: handle %u\n", (unsigned)task, (unsigned)*handle);
  fflush(stdout);
  pthread_mutex_lock(&g_lock);
  ++g_events;
  pthread_cond_broadcast(&g_changed);
  pthread_mutex_unlock(&g_lock);
}

/* The error service routine (task 100, function 5): 1 = heavily disturbed, 2 = bus off. */
static void error_service(USHORT task, USHORT insize, ULONG* status, USHORT outsize,
                          UCHAR* outdata) {
  (void)task;
  (void)insize;
  (void)outsize;
  (void)outdata;
  printf("error service routine: status %lu\n", (unsigned long)*status);
  fflush(stdout);
}

/* Waits until `n` routine calls came, at most 5 s; 0 when they did. */
static int wait_events(unsigned n) {
  struct timespec until;
  int r = 0;
  clock_gettime(CLOCK_REALTIME, &until);
  until.tv_sec += 5;
  pthread_mutex_lock(&g_lock);
  while (g_events < n && r == 0) {
    r = pthread_cond_timedwait(&g_changed, &g_lock, &until);
  }
  pthread_mutex_unlock(&g_lock);
  return g_events >= n ? 0 : -1;
}

static int check(const char* what, UCHAR slot, USHORT error) {
  if (error != 0) {
    fprintf(stderr, "%s (slot %u): error %02Xh, diagnosis %02Xh\n", what, (unsigned)slot,
            (unsigned)error, (unsigned)sl064_get_diagnosis(slot));
    return -1;
  }
  return 0;
}

int main(int argc, char** argv) {
  const UCHAR tx = (UCHAR)(argc > 1 ? atoi(argv[1]) : 1);
  const UCHAR rx = (UCHAR)(argc > 2 ? atoi(argv[2]) : 2);
  const int count = argc > 3 ? atoi(argv[3]) : 3;
  static const USHORT k500k[5] = {100, 16, 3, 1, 1}; /* EEPROM words 15..19 */
  SL064MsgType msg_config;
  SL064Handle hMessage1 = 0;
  SL064Handle hReceive = 0;
  USHORT error;
  UCHAR slot;
  int i;

  canemu_sl064_install_message_service(100, 4, message_service);
  canemu_sl064_install_error_service(100, 5, error_service);
  if (check("sl064_bib_startup", 0, sl064_bib_startup()) != 0) {
    return 1;
  }
  for (slot = 0; slot < 2; ++slot) {
    const UCHAR s = slot == 0 ? tx : rx;
    USHORT w;
    for (w = 0; w < 5; ++w) {
      if (check("EEPROM", s, canemu_sl064_eeprom_write(s, (USHORT)(15 + w), k500k[w])) != 0) {
        return 1;
      }
    }
    if (check("sl064_config_module", s, sl064_config_module(s, 100, 5)) != 0) {
      return 1;
    }
  }

  /* The manual's example object. */
  msg_config.id = 7L;
  msg_config.control_flags = _SL064_SEND | _SL064_ACTIVE | _SL064_PASSIVE;
  msg_config.serv_task = 100;
  msg_config.serv_func = 4;
  error = sl064_config_msg_object(tx, &hMessage1, &msg_config);
  if (check("sl064_config_msg_object", tx, error) != 0) {
    return 1;
  }
  msg_config.control_flags = _SL064_PASSIVE;
  error = sl064_config_msg_object(rx, &hReceive, &msg_config);
  if (check("sl064_config_msg_object", rx, error) != 0 ||
      check("sl064_start_com", tx, sl064_start_com(tx)) != 0 ||
      check("sl064_start_com", rx, sl064_start_com(rx)) != 0) {
    return 1;
  }

  for (i = 0; i < count; ++i) {
    UCHAR out[2];
    UCHAR in[8];
    UCHAR size = sizeof in;
    out[0] = 0xC0;
    out[1] = (UCHAR)i;
    if (check("sl064_set_data", tx, sl064_set_data(tx, hMessage1, out, 2)) != 0 ||
        check("sl064_send_data", tx, sl064_send_data(tx, hMessage1)) != 0) {
      return 1;
    }
    if (wait_events((unsigned)(2 * (i + 1))) != 0) {
      fprintf(stderr, "frame %d: no service routine call within 5 s\n", i);
      return 1;
    }
    sl064_get_data(rx, hReceive, in, &size); /* warning 1 if not 8 bytes came: not an error */
    printf("slot %u received ID 7: %u bytes: %02X %02X\n", (unsigned)rx, (unsigned)size, in[0],
           in[1]);
    fflush(stdout);
  }
  return 0;
}
