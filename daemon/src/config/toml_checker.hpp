// Reading checked TOML: every problem collected with file, line, column and key; nothing is
// applied unless there are none. Shared by the configuration and the fault-scenario loaders.
#pragma once

#include <algorithm>
#include <initializer_list>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <fmt/format.h>
#include <toml++/toml.h>
#include <tl/expected.hpp>

namespace canemu::daemon::detail {

template <typename E>
struct NamedValue {
  E value;
  std::string_view name;
};

template <typename E, std::size_t N>
std::string_view name_of(E value, const NamedValue<E> (&table)[N]) {
  for (const auto& c : table) {
    if (c.value == value) {
      return c.name;
    }
  }
  return "?";
}

// Collects every problem with its place; nothing is applied unless there are none.
class Checker {
 public:
  explicit Checker(std::string file) : file_(std::move(file)) {}

  void error(const toml::source_region& where, std::string_view key, std::string_view what) {
    errors_.push_back(
        fmt::format("{}:{}:{}: {}: {}", file_, where.begin.line, where.begin.column, key, what));
  }
  void error(const toml::node& node, std::string_view key, std::string_view what) {
    error(node.source(), key, what);
  }

  // Every key of `table` not in `allowed` is an error: `complaint`, then the known keys.
  void only_keys(const toml::table& table, std::string_view path,
                 std::span<const std::string_view> allowed,
                 std::string_view complaint = "unknown key (known here: ") {
    for (const auto& [k, v] : table) {
      if (std::find(allowed.begin(), allowed.end(), k.str()) == allowed.end()) {
        std::string known;
        for (auto a : allowed) {
          known += known.empty() ? std::string(a) : ", " + std::string(a);
        }
        (void)v;
        error(k.source(), key(path, k.str()), fmt::format("{}{})", complaint, known));
      }
    }
  }
  void only_keys(const toml::table& table, std::string_view path,
                 std::initializer_list<std::string_view> allowed) {
    only_keys(table, path, std::span<const std::string_view>(allowed.begin(), allowed.size()));
  }

  std::optional<std::string> string(const toml::table& t, std::string_view path,
                                    std::string_view name, bool required) {
    const toml::node* n = t.get(name);
    if (n == nullptr) {
      if (required) {
        error(t.source(), key(path, name), "missing (a string is required)");
      }
      return std::nullopt;
    }
    if (!n->is_string()) {
      error(*n, key(path, name), "must be a string");
      return std::nullopt;
    }
    return std::string(n->as_string()->get());
  }

  std::optional<int64_t> integer(const toml::table& t, std::string_view path, std::string_view name,
                                 bool required, int64_t lo, int64_t hi) {
    const toml::node* n = t.get(name);
    if (n == nullptr) {
      if (required) {
        error(t.source(), key(path, name), "missing (an integer is required)");
      }
      return std::nullopt;
    }
    if (!n->is_integer()) {
      error(*n, key(path, name), "must be an integer");
      return std::nullopt;
    }
    const int64_t v = n->as_integer()->get();
    if (v < lo || v > hi) {
      error(*n, key(path, name), fmt::format("{} is outside {}..{}", v, lo, hi));
      return std::nullopt;
    }
    return v;
  }

  std::optional<double> number(const toml::table& t, std::string_view path, std::string_view name) {
    const toml::node* n = t.get(name);
    if (n == nullptr) {
      return std::nullopt;
    }
    if (n->is_floating_point()) {
      return n->as_floating_point()->get();
    }
    if (n->is_integer()) {
      return static_cast<double>(n->as_integer()->get());
    }
    error(*n, key(path, name), "must be a number");
    return std::nullopt;
  }

  // An array of at most `max` strings (`why` says what to do instead of a longer one).
  std::optional<std::vector<std::string>> strings(const toml::table& t, std::string_view path,
                                                  std::string_view name, std::size_t max = 1024,
                                                  std::string_view why = {}) {
    const toml::node* n = t.get(name);
    if (n == nullptr) {
      return std::nullopt;
    }
    const toml::array* a = n->as_array();
    if (a == nullptr) {
      error(*n, key(path, name), "must be an array of strings");
      return std::nullopt;
    }
    if (a->size() > max) {
      error(*n, key(path, name), fmt::format("{} entries; at most {}{}", a->size(), max, why));
      return std::nullopt;
    }
    std::vector<std::string> out;
    for (const toml::node& e : *a) {
      if (!e.is_string()) {
        error(e, key(path, name), "must be an array of strings");
        return std::nullopt;
      }
      out.emplace_back(e.as_string()->get());
    }
    return out;
  }

  // The table `name` of the root, or nullptr when it is absent or (reported) not a table.
  const toml::table* section(const toml::table& root, std::string_view name) {
    const toml::node* n = root.get(name);
    if (n == nullptr) {
      return nullptr;
    }
    if (n->as_table() == nullptr) {
      error(*n, name, "must be a table");
    }
    return n->as_table();
  }

  // Calls each(table, path) for every table of the array of tables `name` ([[name]]) of the root.
  template <typename Each>
  void for_each_table(const toml::table& root, std::string_view name, Each each) {
    const toml::node* n = root.get(name);
    if (n == nullptr) {
      return;
    }
    const toml::array* a = n->as_array();
    if (a == nullptr) {
      error(*n, name, fmt::format("must be an array of tables ([[{}]])", name));
      return;
    }
    for (std::size_t i = 0; i < a->size(); ++i) {
      const toml::node& e = *a->get(i);
      const std::string path = fmt::format("{}[{}]", name, i);
      if (const toml::table* t = e.as_table()) {
        each(*t, path);
      } else {
        error(e, path, "must be a table");
      }
    }
  }

  // Calls each(table, path) for every table of the array of tables `name` inside `t`
  // ([[PATH.name]]).
  template <typename Each>
  void each_nested(const toml::table& t, const std::string& path, std::string_view name,
                   Each each) {
    const toml::node* n = t.get(name);
    if (n == nullptr) {
      return;
    }
    const toml::array* a = n->as_array();
    if (a == nullptr) {
      error(*n, key(path, name), "must be an array of tables");
      return;
    }
    for (std::size_t i = 0; i < a->size(); ++i) {
      const std::string p = fmt::format("{}.{}[{}]", path, name, i);
      if (const toml::table* e = a->get(i)->as_table()) {
        each(*e, p);
      } else {
        error(*a->get(i), p, "must be a table");
      }
    }
  }

  // A string key whose value must be one of the names of `choices`.
  template <typename E, std::size_t N>
  std::optional<E> choice(const toml::table& t, std::string_view path, std::string_view name,
                          bool required, const NamedValue<E> (&choices)[N], std::string_view what) {
    auto text = string(t, path, name, required);
    if (!text) {
      return std::nullopt;
    }
    for (const auto& c : choices) {
      if (c.name == *text) {
        return c.value;
      }
    }
    std::string known;
    for (const auto& c : choices) {
      known += known.empty() ? std::string(c.name) : ", " + std::string(c.name);
    }
    error(*t.get(name), key(path, name),
          fmt::format("\"{}\" is not a {} ({})", *text, what, known));
    return std::nullopt;
  }

  static std::string key(std::string_view path, std::string_view name) {
    return path.empty() ? std::string(name) : fmt::format("{}.{}", path, name);
  }

  std::vector<std::string>& errors() { return errors_; }
  const std::string& file() const { return file_; }

 private:
  std::string file_;
  std::vector<std::string> errors_;
};

// `text` as TOML, or its syntax error as the one problem "SOURCE:LINE:COLUMN: what".
inline tl::expected<toml::table, std::vector<std::string>> parse_toml(std::string_view text,
                                                                      const std::string& source) {
  try {
    return toml::parse(text, source);
  } catch (const toml::parse_error& e) {
    return tl::unexpected(std::vector<std::string>{fmt::format(
        "{}:{}:{}: {}", source, e.source().begin.line, e.source().begin.column, e.description())});
  }
}

}  // namespace canemu::daemon::detail
