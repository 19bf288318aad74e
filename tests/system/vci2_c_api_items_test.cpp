// Checklist items of the VCI digest (§7) through the VCI "2" C API (libvcinpl2).
#include <gtest/gtest.h>

namespace canemu {
namespace {}  // namespace
}  // namespace canemu
