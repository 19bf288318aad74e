// The device objects of the VCI C++ API: the device manager (IVciDeviceManager) with its
// enumerator (IVciEnumDevice), a device (IVciDevice) and its bus access layer (IBalObject).
#pragma once

#include "vci_core.hpp"
#include "vcisdk.h"

namespace canemu::client::vci::cpp {

// New objects with one reference each.
IVciDeviceManager* new_device_manager();
IVciDevice* new_device(DeviceDesc d);

}  // namespace canemu::client::vci::cpp
