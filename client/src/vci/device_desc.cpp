// Devices as the VCI shows them: VCIDEVICEINFO and VCIDEVICECAPS of a device of canemud's
// list, canemu's device class identifiers, and finding a device by VCIID, hardware ID or class.
#include <cstdio>
#include <cstring>
#include <optional>
#include <string>
#include <vector>

#include "vci_core.hpp"

namespace canemu::client::vci {

GUID device_class(uint8_t model) {
  // canemu's own class identifiers, one per emulated adapter model.
  GUID g{0x6a4c1e3bU, 0x2c0d, 0x4e7a, {0x9b, 0x41, 0x5d, 0x3f, 0x10, 0x8e, 0x77, 0xa2}};
  g.Data4[7] = static_cast<UINT8>(g.Data4[7] + model);
  return g;
}

VCIDEVICEINFO DeviceDesc::info() const {
  VCIDEVICEINFO d{};
  d.VciObjectId.AsInt64 = static_cast<INT64>(vci_id);
  d.DeviceClass = device_class(model);
  d.DriverMajorVersion = 1;
  d.DriverMinorVersion = 0;
  d.DriverBuildVersion = 0;
  d.HardwareBranchVersion = 0;
  d.HardwareMajorVersion = 1;
  d.HardwareMinorVersion = 0;
  d.HardwareBuildVersion = 0;
  std::snprintf(d.UniqueHardwareId.AsChar, sizeof d.UniqueHardwareId.AsChar, "%s",
                hardware_id.c_str());
  const char* product = model == static_cast<uint8_t>(ipc::WireDeviceModel::ixxat_usb_to_can_fd)
                            ? "USB-to-CAN FD"
                            : "USB-to-CAN";
  std::snprintf(d.Description, sizeof d.Description, "%s (canemu %s)", product, name.c_str());
  std::snprintf(d.Manufacturer, sizeof d.Manufacturer, "canemu");
  return d;
}

VCIDEVICECAPS DeviceDesc::caps() const {
  VCIDEVICECAPS c{};
  c.BusCtrlCount = static_cast<UINT16>(controller_fd.size());
  for (std::size_t i = 0; i < controller_fd.size() && i < VCI_MAX_BUSCTRL; ++i) {
    c.BusCtrlTypes[i] = static_cast<UINT16>(
        controller_lin[i]
            ? VCI_LIN_CTRL(LIN_CTRL_UNKNOWN)
            : VCI_BUS_CTRL(VCI_BUS_CAN, controller_fd[i] ? CAN_CTRL_IFICFD : CAN_CTRL_SJA1000));
  }
  return c;
}

namespace {
// "0 (can0)", "0 (can0) and 1 (can1)", "0 (a), 1 (b) and 2 (c)".
std::string numbered(const std::vector<std::string>& items) {
  std::string out;
  for (std::size_t i = 0; i < items.size(); ++i) {
    out += (i == 0 ? "" : i + 1 == items.size() ? " and " : ", ") + items[i];
  }
  return out;
}
}  // namespace

std::string no_can_controller(const DeviceDesc& device, uint32_t asked) {
  std::vector<std::string> can;
  std::vector<std::string> lin;
  for (std::size_t i = 0; i < device.controller_lin.size(); ++i) {
    const std::string bus = i < device.buses.size() ? device.buses[i] : "";
    (device.controller_lin[i] ? lin : can).push_back(std::to_string(i) + " (" + bus + ")");
  }
  const std::string can_text =
      can.empty() ? "it has no CAN controller"
                  : (can.size() == 1 ? "its CAN controller is " : "its CAN controllers are ") +
                        numbered(can);
  const bool is_lin = asked < device.controller_lin.size() && device.controller_lin[asked];
  if (is_lin) {
    const std::string bus = asked < device.buses.size() ? device.buses[asked] : "";
    return "controller " + std::to_string(asked) + " of " + device.name +
           " is its LIN controller (" + bus + "); " + can_text;
  }
  std::string text = device.name + " has no controller " + std::to_string(asked) + "; " + can_text;
  if (lin.size() == 1) {
    const std::size_t open = lin[0].find(" (");
    text += ", " + lin[0].substr(0, open) + " is its LIN controller" + lin[0].substr(open);
  } else if (!lin.empty()) {
    text += ", " + numbered(lin) + " are its LIN controllers";
  }
  return text;
}

namespace {
template <class Match>
std::optional<DeviceDesc> device_where(Match match, HRESULT none, HRESULT& hr) {
  std::vector<DeviceDesc> devices;
  hr = Library::get().list_devices(devices);
  if (hr != VCI_OK) {
    return std::nullopt;
  }
  for (DeviceDesc& d : devices) {
    if (match(d)) {
      return std::move(d);
    }
  }
  hr = none;
  return std::nullopt;
}
bool same_guid(const GUID& a, const GUID& b) {
  return std::memcmp(&a, &b, sizeof a) == 0;
}
}  // namespace

std::optional<DeviceDesc> device_by_id(int64_t vci_id, HRESULT& hr) {
  auto d = device_where(
      [vci_id](const DeviceDesc& x) { return static_cast<int64_t>(x.vci_id) == vci_id; },
      VCI_E_INVALIDARG, hr);
  if (!d && hr == VCI_E_INVALIDARG) {
    set_detail("no device has that VCIID");
  }
  return d;
}

std::optional<DeviceDesc> device_by_hwid(const GUID& hwid, HRESULT& hr) {
  return device_where(
      [&hwid](const DeviceDesc& x) { return same_guid(x.info().UniqueHardwareId.AsGuid, hwid); },
      VCI_E_NO_MORE_ITEMS, hr);
}

std::optional<DeviceDesc> device_by_class(const GUID& cls, uint32_t instance, HRESULT& hr) {
  uint32_t seen = 0;
  return device_where(
      [&](const DeviceDesc& x) {
        return same_guid(device_class(x.model), cls) && seen++ == instance;
      },
      VCI_E_NO_MORE_ITEMS, hr);
}

}  // namespace canemu::client::vci
