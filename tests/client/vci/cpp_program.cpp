// A VCI C++ program built with only `pkg-config --cflags --libs canemu-vciapi`
// (pkg_config_test.sh).
#include <stdio.h>

#include <vcisdk.h>

int main() {
  char text[256];
  VciFormatError(VCI_E_TIMEOUT, text, sizeof text);
  printf("CANBTP %u bytes; VCI_E_TIMEOUT: %s\n", static_cast<unsigned>(sizeof(CANBTP)), text);
  return 0;
}
