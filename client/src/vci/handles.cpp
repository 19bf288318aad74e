// The handles of the VCI C libraries (every live object, checked before use), the C++ API's
// objects as aliases of the remote objects they hold, and what a remote object and a channel's
// rings do when made and destroyed.
#include <map>
#include <memory>
#include <mutex>
#include <set>

#include "requests.hpp"
#include "vci_core.hpp"

namespace canemu::client::vci {

namespace {

struct Registry {
  std::mutex mutex;
  std::set<Object*> live;
  std::map<const void*, Remote*> aliases;
};

Registry& registry() {
  static Registry* r = new Registry;  // never destroyed: handles may outlive static teardown
  return *r;
}

}  // namespace

void* register_object(std::unique_ptr<Object> object) {
  Registry& r = registry();
  std::lock_guard lock(r.mutex);
  Object* p = object.release();
  r.live.insert(p);
  return p;
}

Object* lookup(void* handle, Object::Kind kind) {
  forget_call_detail();
  Registry& r = registry();
  std::lock_guard lock(r.mutex);
  auto* p = static_cast<Object*>(handle);
  if (r.live.count(p) == 0 || p->kind() != kind) {
    return nullptr;
  }
  return p;
}

bool unregister_object(void* handle, Object::Kind kind) {
  forget_call_detail();
  std::unique_ptr<Object> doomed;
  {
    Registry& r = registry();
    std::lock_guard lock(r.mutex);
    auto* p = static_cast<Object*>(handle);
    if (r.live.count(p) == 0 || p->kind() != kind) {
      return false;
    }
    r.live.erase(p);
    doomed.reset(p);
  }
  return true;  // destroyed here, outside the registry's lock
}

void register_alias(const void* key, Remote* remote) {
  Registry& r = registry();
  std::lock_guard lock(r.mutex);
  r.aliases[key] = remote;
}

void unregister_alias(const void* key) {
  Registry& r = registry();
  std::lock_guard lock(r.mutex);
  r.aliases.erase(key);
}

Remote* alias_of(const void* key) {
  Registry& r = registry();
  std::lock_guard lock(r.mutex);
  auto it = r.aliases.find(key);
  return it == r.aliases.end() ? nullptr : it->second;
}

Remote::~Remote() {
  req::simple(*this, ipc::VciOp::close);
}

Rings::Rings(ipc::RingPair mapped, bool with_tx)
    : pair(std::move(mapped)), rx(pair.rx().reader()), tx(pair.tx().writer()), has_tx(with_tx) {}

}  // namespace canemu::client::vci
