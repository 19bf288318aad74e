#include "canemu/daemon/world/device_registry.hpp"

#include <fmt/format.h>

namespace canemu::daemon {

std::string hardware_id(std::string_view device_name) {
  uint32_t h = 2166136261U;  // FNV-1a
  for (char ch : device_name) {
    h = (h ^ static_cast<uint8_t>(ch)) * 16777619U;
  }
  return fmt::format("HW{:06}", h % 1'000'000);
}

void DeviceRegistry::add_configured(DeviceConfig config, std::vector<Controller> controllers,
                                    std::vector<LinController> lin) {
  configured_.push_back(
      Configured{std::move(config), std::move(controllers), next_vci_id_++, std::move(lin)});
}

void DeviceRegistry::add_ephemeral(const std::string& name, std::size_t bus,
                                   model::HostedNode& node, uint32_t owner_pid,
                                   std::shared_ptr<model::ixxat::CanLine> line) {
  const uint64_t vci_id = line ? next_vci_id_++ : 0;
  ephemeral_.push_back(Ephemeral{name, bus, &node, owner_pid, std::move(line), vci_id});
  announce(ipc::NotificationKind::device_added, name);
}

void DeviceRegistry::add_lin_ephemeral(const std::string& name, std::size_t bus, uint32_t owner_pid,
                                       std::shared_ptr<model::ixxat::LinLine> line) {
  lin_ephemeral_.push_back(LinEphemeral{name, bus, owner_pid, std::move(line), next_vci_id_++});
  announce(ipc::NotificationKind::device_added, name);
}

void DeviceRegistry::remove_ephemeral(std::string_view name) {
  const std::string gone(name);
  std::erase_if(ephemeral_, [&](const Ephemeral& e) { return e.name == gone; });
  std::erase_if(lin_ephemeral_, [&](const LinEphemeral& e) { return e.name == gone; });
  announce(ipc::NotificationKind::device_removed, gone);
}

void DeviceRegistry::announce(ipc::NotificationKind kind, const std::string& name) {
  ++generation_;
  if (on_change) {
    on_change(kind, name);
  }
}

const DeviceRegistry::Ephemeral* DeviceRegistry::find_ephemeral(std::string_view name) const {
  for (const Ephemeral& e : ephemeral_) {
    if (e.name == name) {
      return &e;
    }
  }
  return nullptr;
}

std::shared_ptr<XcanDevice> DeviceRegistry::find_xcan(std::string_view name) const {
  for (const Xcan& x : xcan_) {
    if (x.config.name == name) {
      return x.device;
    }
  }
  return nullptr;
}

std::shared_ptr<SlcanDevice> DeviceRegistry::find_slcan_slot(unsigned slot) const {
  for (const Slcan& s : slcan_) {
    if (s.device->module().slot() == slot) {
      return s.device;
    }
  }
  return nullptr;
}

bool DeviceRegistry::exists(std::string_view name) const {
  for (const Configured& d : configured_) {
    if (d.config.name == name) {
      return true;
    }
  }
  if (find_xcan(name) != nullptr) {
    return true;
  }
  for (const LinEphemeral& e : lin_ephemeral_) {
    if (e.name == name) {
      return true;
    }
  }
  for (const Slcan& s : slcan_) {
    if (s.config.name == name) {
      return true;
    }
  }
  return find_ephemeral(name) != nullptr;
}

std::string DeviceRegistry::unique_name(std::string_view prefix) const {
  for (uint64_t k = 1;; ++k) {
    std::string name = fmt::format("{}{}", prefix, k);
    if (!exists(name)) {
      return name;
    }
  }
}

std::optional<DeviceRegistry::NodeRef> DeviceRegistry::find_node(std::string_view name) const {
  for (const Configured& d : configured_) {
    for (const Controller& c : d.controllers) {
      if (c.name == name) {
        return NodeRef{c.bus, c.node.get(), c.node->node(), &c.node->controller(), nullptr, 0};
      }
    }
  }
  for (const Ephemeral& e : ephemeral_) {
    if (e.name == name || e.name + ":0" == name) {
      return NodeRef{e.bus, e.node, e.node->node(), &e.node->controller(), nullptr, 0};
    }
  }
  for (const Xcan& x : xcan_) {
    for (unsigned i = 0; i < x.buses.size(); ++i) {
      if (fmt::format("{}:{}", x.config.name, i) == name) {
        model::I82527& chip = x.device->module().chip(i);
        return NodeRef{x.buses[i], nullptr, chip.node(), &chip, x.device, i};
      }
    }
  }
  for (const Slcan& s : slcan_) {
    if (s.config.name + ":0" == name) {
      model::I82527& chip = s.device->module().chip();
      return NodeRef{s.bus, nullptr, chip.node(), &chip, nullptr, 0};
    }
  }
  return std::nullopt;
}

std::optional<std::string> DeviceRegistry::node_name(std::size_t bus, model::NodeId node) const {
  for (const Configured& d : configured_) {
    for (const Controller& c : d.controllers) {
      if (c.bus == bus && c.node->node() == node) {
        return c.name;
      }
    }
  }
  for (const Ephemeral& e : ephemeral_) {
    if (e.bus == bus && e.node->node() == node) {
      return e.name + ":0";
    }
  }
  for (const Xcan& x : xcan_) {
    for (unsigned i = 0; i < x.buses.size(); ++i) {
      if (x.buses[i] == bus && x.device->module().chip(i).node() == node) {
        return fmt::format("{}:{}", x.config.name, i);
      }
    }
  }
  for (const Slcan& s : slcan_) {
    if (s.bus == bus && s.device->module().chip().node() == node) {
      return s.config.name + ":0";
    }
  }
  return std::nullopt;
}

std::shared_ptr<model::ixxat::CanLine> DeviceRegistry::vci_line(std::string_view device,
                                                                uint32_t controller) const {
  for (const Configured& d : configured_) {
    if (d.config.name == device) {
      return controller < d.controllers.size() ? d.controllers[controller].line : nullptr;
    }
  }
  const Ephemeral* e = find_ephemeral(device);
  return e != nullptr && controller == 0 ? e->line : nullptr;
}

std::shared_ptr<model::ixxat::LinLine> DeviceRegistry::vci_lin_line(std::string_view device,
                                                                    uint32_t controller) const {
  for (const Configured& d : configured_) {
    if (d.config.name == device) {
      const std::size_t can = d.controllers.size();
      return controller >= can && controller - can < d.lin.size() ? d.lin[controller - can].line
                                                                  : nullptr;
    }
  }
  for (const LinEphemeral& e : lin_ephemeral_) {
    if (e.name == device) {
      return controller == 0 ? e.line : nullptr;
    }
  }
  return nullptr;
}

std::shared_ptr<model::ixxat::CanLine> DeviceRegistry::vci_line_of(
    const model::HostedNode* node) const {
  for (const Configured& d : configured_) {
    for (const Controller& c : d.controllers) {
      if (c.node.get() == node) {
        return c.line;
      }
    }
  }
  for (const Ephemeral& e : ephemeral_) {
    if (e.node == node) {
      return e.line;
    }
  }
  return nullptr;
}

uint64_t DeviceRegistry::vci_id_of(std::string_view device) const {
  for (const Configured& d : configured_) {
    if (d.config.name == device) {
      return d.vci_id;
    }
  }
  for (const LinEphemeral& l : lin_ephemeral_) {
    if (l.name == device) {
      return l.vci_id;
    }
  }
  const Ephemeral* e = find_ephemeral(device);
  return e != nullptr && e->line ? e->vci_id : 0;
}

}  // namespace canemu::daemon
