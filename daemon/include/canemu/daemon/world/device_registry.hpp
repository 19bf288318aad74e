// The devices canemud shows (the VCI device list, `canemu status`, fault scenarios' node
// names): configured adapters with the controllers built for them, and ephemeral devices that
// clients make while they are connected.
//
// Names resolve to nodes here: a configured controller is "DEVICE:N", an ephemeral device's
// node "NAME" or "NAME:0". VCI adapters have a VciObjectId (configured ones in configuration
// order, ephemeral ones as they come; never reused) and a hardware ID. Every change counts in
// generation() and is told to on_change. Bookkeeping only: the registry does not make, start or
// stop nodes (Simulation builds them; NodePool keeps the ephemeral devices' nodes).
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "canemu/daemon/config/config.hpp"
#include "canemu/daemon/world/slcan_device.hpp"
#include "canemu/daemon/world/xcan_device.hpp"
#include "canemu/firmware_model/adapters/ixxat/can_line.hpp"
#include "canemu/firmware_model/adapters/ixxat/lin_line.hpp"
#include "canemu/firmware_model/chips/hosted_node.hpp"
#include "canemu/ipc/protocol.hpp"

namespace canemu::daemon {

// The VCI hardware ID of a device: "HW" and six digits from its name, so that it stays the same
// from run to run.
std::string hardware_id(std::string_view device_name);

class DeviceRegistry {
 public:
  struct Controller {
    std::string name;  // "DEVICE:N"
    std::size_t bus;
    std::unique_ptr<model::HostedNode> node;
    std::shared_ptr<model::ixxat::CanLine> line;  // the adapter firmware driving it
  };
  // A LIN controller of an IXXAT adapter, numbered after the adapter's CAN controllers.
  struct LinController {
    std::string name;  // "DEVICE:N"
    std::size_t bus;
    std::shared_ptr<model::ixxat::LinLine> line;  // the adapter firmware with the controller
  };
  struct Configured {
    DeviceConfig config;
    std::vector<Controller> controllers;  // controller N is config.controllers[N]'s
    uint64_t vci_id;
    std::vector<LinController> lin;  // controller controllers.size() + i is config.lin[i]'s
  };
  struct Ephemeral {
    std::string name;
    std::size_t bus;
    model::HostedNode* node;  // the pool's
    uint32_t owner_pid;
    std::shared_ptr<model::ixxat::CanLine> line;  // VCI adapters only
    uint64_t vci_id = 0;                          // VCI adapters only
  };
  // An ephemeral VCI adapter with one LIN controller (controller 0, "NAME:0") on a LIN bus.
  struct LinEphemeral {
    std::string name;
    std::size_t bus;
    uint32_t owner_pid;
    std::shared_ptr<model::ixxat::LinLine> line;
    uint64_t vci_id = 0;
  };
  // A configured SORCUS X-CAN-2i; its interface N is the node "NAME:N" on buses[N].
  struct Xcan {
    DeviceConfig config;
    std::vector<std::size_t> buses;
    std::shared_ptr<XcanDevice> device;
  };
  // A configured SORCUS SL-CANi; its interface is the node "NAME:0" on `bus`.
  struct Slcan {
    DeviceConfig config;
    std::size_t bus;
    std::shared_ptr<SlcanDevice> device;
  };
  struct NodeRef {
    std::size_t bus;
    model::HostedNode* node;  // nullptr for an X-CAN interface (the module drives its chip)
    model::NodeId id = 0;
    model::CanController* controller = nullptr;
    std::shared_ptr<XcanDevice> xcan;  // an X-CAN interface: its device and `iface`
    unsigned iface = 0;
  };

  // A configured device, with its controllers in configuration order. Not counted as a change:
  // at start-up nobody is told; a reload announces it.
  void add_configured(DeviceConfig config, std::vector<Controller> controllers,
                      std::vector<LinController> lin = {});
  void add_xcan(Xcan device) { xcan_.push_back(std::move(device)); }
  const std::vector<Xcan>& xcan() const { return xcan_; }
  // The X-CAN-2i named `name`, or nullptr.
  std::shared_ptr<XcanDevice> find_xcan(std::string_view name) const;
  void add_slcan(Slcan device) { slcan_.push_back(std::move(device)); }
  const std::vector<Slcan>& slcan() const { return slcan_; }
  // The SL-CANi in `slot`, or nullptr.
  std::shared_ptr<SlcanDevice> find_slcan_slot(unsigned slot) const;

  // An ephemeral device with its one node; a VCI adapter when `line` is set.
  void add_ephemeral(const std::string& name, std::size_t bus, model::HostedNode& node,
                     uint32_t owner_pid, std::shared_ptr<model::ixxat::CanLine> line = nullptr);
  void add_lin_ephemeral(const std::string& name, std::size_t bus, uint32_t owner_pid,
                         std::shared_ptr<model::ixxat::LinLine> line);
  // Removes the ephemeral device `name`, CAN or LIN.
  void remove_ephemeral(std::string_view name);
  // Counts a change and tells on_change (add_ephemeral and remove_ephemeral do so themselves).
  void announce(ipc::NotificationKind kind, const std::string& name);

  const std::vector<Configured>& configured() const { return configured_; }
  const std::vector<Ephemeral>& ephemeral() const { return ephemeral_; }  // in order of creation
  const std::vector<LinEphemeral>& lin_ephemeral() const { return lin_ephemeral_; }
  const Ephemeral* find_ephemeral(std::string_view name) const;
  bool exists(std::string_view name) const;
  // A name no device has: `prefix` followed by the smallest number from 1 on.
  std::string unique_name(std::string_view prefix) const;

  std::optional<NodeRef> find_node(std::string_view name) const;
  // The name of node `node` of bus `bus`, if a device's.
  std::optional<std::string> node_name(std::size_t bus, model::NodeId node) const;
  // The adapter firmware of controller `controller` of the VCI device `device`; nullptr if
  // there is none. Shared: objects a client opened keep it running after an ephemeral device
  // has gone.
  std::shared_ptr<model::ixxat::CanLine> vci_line(std::string_view device,
                                                  uint32_t controller) const;
  // The LIN firmware of controller `controller` (the VCI's bus number: after the CAN
  // controllers) of the VCI device `device`; nullptr if it is not a LIN controller.
  std::shared_ptr<model::ixxat::LinLine> vci_lin_line(std::string_view device,
                                                      uint32_t controller) const;
  // The firmware driving `node`, if a VCI adapter's.
  std::shared_ptr<model::ixxat::CanLine> vci_line_of(const model::HostedNode* node) const;
  // The VciObjectId of a VCI device; 0 if there is none.
  uint64_t vci_id_of(std::string_view device) const;

  uint32_t generation() const { return generation_; }
  // Told of every device that comes or goes.
  std::function<void(ipc::NotificationKind, const std::string&)> on_change;

 private:
  std::vector<Configured> configured_;
  std::vector<Ephemeral> ephemeral_;
  std::vector<LinEphemeral> lin_ephemeral_;
  std::vector<Xcan> xcan_;
  std::vector<Slcan> slcan_;
  uint32_t generation_ = 0;
  uint64_t next_vci_id_ = 1;
};

}  // namespace canemu::daemon
