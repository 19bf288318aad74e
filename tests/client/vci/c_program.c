/* A VCI C program built as an application builder would: its flags only from
 * `pkg-config --cflags --libs canemu-vcinpl2` (pkg_config_test.sh). It needs an API header and
 * a data-type header, which live apart in the source tree. */
#include <stdio.h>

#include <cantype.h>
#include <vcinpl2.h>

int main(void) {
  char text[VCI_MAX_ERRSTRLEN];
  vciFormatError(VCI_E_TIMEOUT, text, sizeof text);
  printf("CANCAPABILITIES2 %u bytes; VCI_E_TIMEOUT: %s\n", (unsigned)sizeof(CANCAPABILITIES2),
         text);
  return 0;
}
