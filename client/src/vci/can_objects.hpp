// The CAN objects of the VCI C++ API that a BAL opens on one of its controllers: the socket
// (ICanSocket, ICanSocket2), the control unit (ICanControl, ICanControl2) and the cyclic list
// (ICanScheduler, ICanScheduler2); a socket creates channels (ICanChannel, ICanChannel2).
#pragma once

#include "vci_core.hpp"
#include "vcisdk.h"

namespace canemu::client::vci::cpp {

// What the socket, control and channel objects have in common: the controller they are on.
struct Bus {
  DeviceDesc device;
  UINT32 no = 0;
};

// The socket, control unit or cyclic list `riid` names on `bus` (IBalObject::OpenSocket once
// its arguments are checked); VCI_E_NOINTERFACE for any other interface.
HRESULT open_socket(const Bus& bus, REFIID riid, PVOID* ppv);

// The same for a LIN controller (lin_objects.cpp): ILinSocket or ILinControl.
HRESULT open_lin_socket(const Bus& bus, REFIID riid, PVOID* ppv);

// ICanSocket::GetSocketInfo and ILinSocket::GetSocketInfo.
HRESULT socket_info(const Bus& bus, PBALSOCKETINFO p);

}  // namespace canemu::client::vci::cpp
