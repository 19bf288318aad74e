// What every VCI library reports the same way: its version, new LUIDs, identifiers as text,
// and the conversions between UTF-8 and wide text that the W functions need.
#include <atomic>
#include <cinttypes>
#include <cstdio>
#include <cstring>

#include <unistd.h>

#include "vci_core.hpp"

namespace canemu::client::vci {

uint32_t vci_build_number() {
  return CANEMU_VERSION_NUMBER;
}

int64_t new_luid() {
  static std::atomic<uint32_t> next{1};
  return static_cast<int64_t>((static_cast<uint64_t>(::getpid()) << 32) | next++);
}

namespace {

int hex(char c) {
  if (c >= '0' && c <= '9') {
    return c - '0';
  }
  if (c >= 'a' && c <= 'f') {
    return c - 'a' + 10;
  }
  if (c >= 'A' && c <= 'F') {
    return c - 'A' + 10;
  }
  return -1;
}

// Reads `digits` hex digits from the front of `text` into `out` and drops them; false on
// anything else.
bool read_hex(std::string_view& text, std::size_t digits, uint64_t& out) {
  if (text.size() < digits) {
    return false;
  }
  out = 0;
  for (std::size_t i = 0; i < digits; ++i) {
    const int v = hex(text[i]);
    if (v < 0) {
      return false;
    }
    out = (out << 4) | static_cast<uint64_t>(v);
  }
  text.remove_prefix(digits);
  return true;
}

bool read_char(std::string_view& text, char c) {
  if (text.empty() || text.front() != c) {
    return false;
  }
  text.remove_prefix(1);
  return true;
}

}  // namespace

std::string luid_text(const VCIID& id) {
  char text[kLuidTextLength + 1];
  std::snprintf(text, sizeof text, "%016" PRIX64, static_cast<uint64_t>(id.AsInt64));
  return text;
}

std::string guid_text(const GUID& g) {
  char text[kGuidTextLength + 1];
  std::snprintf(text, sizeof text, "{%08" PRIX32 "-%04X-%04X-%02X%02X-%02X%02X%02X%02X%02X%02X}",
                g.Data1, g.Data2, g.Data3, g.Data4[0], g.Data4[1], g.Data4[2], g.Data4[3],
                g.Data4[4], g.Data4[5], g.Data4[6], g.Data4[7]);
  return text;
}

std::optional<VCIID> parse_luid(std::string_view text) {
  uint64_t v = 0;
  if (text.size() != kLuidTextLength || !read_hex(text, kLuidTextLength, v)) {
    return std::nullopt;
  }
  VCIID id{};
  id.AsInt64 = static_cast<INT64>(v);
  return id;
}

std::optional<GUID> parse_guid(std::string_view text) {
  uint64_t a = 0;
  uint64_t b = 0;
  uint64_t c = 0;
  uint64_t d = 0;
  uint64_t e = 0;
  const bool ok = text.size() == kGuidTextLength && read_char(text, '{') && read_hex(text, 8, a) &&
                  read_char(text, '-') && read_hex(text, 4, b) && read_char(text, '-') &&
                  read_hex(text, 4, c) && read_char(text, '-') && read_hex(text, 4, d) &&
                  read_char(text, '-') && read_hex(text, 12, e) && read_char(text, '}');
  if (!ok) {
    return std::nullopt;
  }
  GUID g{};
  g.Data1 = static_cast<UINT32>(a);
  g.Data2 = static_cast<UINT16>(b);
  g.Data3 = static_cast<UINT16>(c);
  g.Data4[0] = static_cast<UINT8>(d >> 8);
  g.Data4[1] = static_cast<UINT8>(d);
  for (int i = 0; i < 6; ++i) {
    g.Data4[2 + i] = static_cast<UINT8>(e >> (40 - 8 * i));
  }
  return g;
}

std::wstring widen(std::string_view utf8) {
  std::wstring out;
  std::size_t i = 0;
  while (i < utf8.size()) {
    const auto b = static_cast<unsigned char>(utf8[i]);
    std::size_t extra = 0;
    uint32_t cp = 0;
    if (b < 0x80) {
      cp = b;
    } else if ((b & 0xE0U) == 0xC0U) {
      extra = 1;
      cp = b & 0x1FU;
    } else if ((b & 0xF0U) == 0xE0U) {
      extra = 2;
      cp = b & 0x0FU;
    } else if ((b & 0xF8U) == 0xF0U) {
      extra = 3;
      cp = b & 0x07U;
    } else {
      out.push_back(L'\uFFFD');
      ++i;
      continue;
    }
    bool ok = i + extra < utf8.size();
    for (std::size_t k = 1; ok && k <= extra; ++k) {
      const auto c = static_cast<unsigned char>(utf8[i + k]);
      ok = (c & 0xC0U) == 0x80U;
      cp = (cp << 6) | (c & 0x3FU);
    }
    if (!ok) {
      out.push_back(L'\uFFFD');
      ++i;
      continue;
    }
    out.push_back(static_cast<wchar_t>(cp));
    i += extra + 1;
  }
  return out;
}

std::string narrow(std::wstring_view wide) {
  std::string out;
  for (const wchar_t w : wide) {
    auto cp = static_cast<uint32_t>(w);
    if (cp > 0x10FFFFU || (cp >= 0xD800U && cp <= 0xDFFFU)) {
      cp = 0xFFFDU;
    }
    if (cp < 0x80U) {
      out.push_back(static_cast<char>(cp));
    } else if (cp < 0x800U) {
      out.push_back(static_cast<char>(0xC0U | (cp >> 6)));
      out.push_back(static_cast<char>(0x80U | (cp & 0x3FU)));
    } else if (cp < 0x10000U) {
      out.push_back(static_cast<char>(0xE0U | (cp >> 12)));
      out.push_back(static_cast<char>(0x80U | ((cp >> 6) & 0x3FU)));
      out.push_back(static_cast<char>(0x80U | (cp & 0x3FU)));
    } else {
      out.push_back(static_cast<char>(0xF0U | (cp >> 18)));
      out.push_back(static_cast<char>(0x80U | ((cp >> 12) & 0x3FU)));
      out.push_back(static_cast<char>(0x80U | ((cp >> 6) & 0x3FU)));
      out.push_back(static_cast<char>(0x80U | (cp & 0x3FU)));
    }
  }
  return out;
}

std::optional<std::string> narrow_ascii(std::wstring_view wide) {
  std::string out;
  for (const wchar_t w : wide) {
    if (w <= 0 || w >= 0x80) {
      return std::nullopt;
    }
    out.push_back(static_cast<char>(w));
  }
  return out;
}

namespace {

template <class Char>
HRESULT copy_out(const std::string& text, Char* out, LONG size) {
  if (out == nullptr || size <= 0) {
    return VCI_E_INVALIDARG;
  }
  if (text.size() + 1 > static_cast<std::size_t>(size)) {
    return VCI_E_BUFFER_OVERFLOW;
  }
  for (std::size_t i = 0; i < text.size(); ++i) {
    out[i] = static_cast<Char>(static_cast<unsigned char>(text[i]));
  }
  out[text.size()] = Char{};
  return VCI_OK;
}

}  // namespace

HRESULT copy_text(const std::string& text, char* out, LONG size) {
  return copy_out(text, out, size);
}

HRESULT copy_text(const std::string& text, wchar_t* out, LONG size) {
  return copy_out(text, out, size);
}

}  // namespace canemu::client::vci
