// The COM-like base of every object of the VCI C++ API: reference counting and
// QueryInterface (Com), and the helpers that hand an object out through a `void**`.
#pragma once

#include <atomic>
#include <cstring>

#include "vcisdk.h"

namespace canemu::client::vci::cpp {

inline bool same(const GUID& a, const GUID& b) {
  return std::memcmp(&a, &b, sizeof a) == 0;
}

// The IUnknown part of every object: `Interface` is what it implements, `iid` its identifier
// (QueryInterface gives the object itself for it and for IID_IUnknown).
template <class Interface, const IID& iid>
class Com : public Interface {
 public:
  Com() = default;
  Com(const Com&) = delete;
  Com& operator=(const Com&) = delete;
  HRESULT QueryInterface(REFIID riid, PVOID* ppv) override {
    if (ppv == nullptr) {
      return VCI_E_INVALIDARG;
    }
    if (same(riid, iid) || same(riid, IID_IUnknown)) {
      this->AddRef();
      *ppv = static_cast<Interface*>(this);
      return VCI_OK;
    }
    *ppv = nullptr;
    return VCI_E_NOINTERFACE;
  }
  ULONG AddRef() override { return ++refs_; }
  ULONG Release() override {
    const ULONG n = --refs_;
    if (n == 0) {
      delete this;
    }
    return n;
  }

 protected:
  virtual ~Com() = default;

 private:
  std::atomic<ULONG> refs_{1};
};

template <class T>
HRESULT hand_out(T* object, PVOID* ppv) {
  *ppv = object;
  return VCI_OK;
}

template <class P>
bool null_out(P** pp) {
  if (pp == nullptr) {
    return false;
  }
  *pp = nullptr;
  return true;
}

}  // namespace canemu::client::vci::cpp
