// canhil/emulator/table_reader.hpp — one table of a canhil TOML file (a
// scenario's [run], [coach], ...; a test file's [test], [[events]],
// [[expect]]): its fields with their lines, unknown fields refused, mistakes
// as physics::ConfigError, `FILE:LINE: TABLE.FIELD: what; what to do`.
#pragma once

#include <toml++/toml.h>

#include <algorithm>
#include <cstdio>
#include <optional>
#include <string>
#include <vector>

#include "canhil/can_nodes/node_ids.hpp"
#include "canhil/physics/config.hpp"

namespace canhil::emulator {

class TableReader {
 public:
  TableReader(const toml::table& table, std::string name, const std::string& file, std::vector<std::string> known)
      : table_(table), name_(std::move(name)), file_(file) {
    for (const auto& [k, v] : table_) {
      if (std::find(known.begin(), known.end(), k.str()) != known.end()) continue;
      std::string list;
      for (const auto& n : known) list += (list.empty() ? "" : ", ") + n;
      fail(v, std::string(k.str()), "unknown field; known here: " + list);
    }
  }
  [[noreturn]] void fail(const toml::node& at, const std::string& key, const std::string& what) const {
    throw physics::ConfigError(file_, static_cast<int>(at.source().begin.line), name_ + "." + key, what);
  }
  const toml::node* get(const std::string& key) const { return table_.get(key); }
  const toml::array* array(const std::string& key) const {
    const toml::node* n = get(key);
    if (n == nullptr) return nullptr;
    if (!n->is_array()) fail(*n, key, "must be a list, e.g. " + key + " = [...]");
    return n->as_array();
  }
  std::optional<std::string> text(const std::string& key, const char* example) const {
    const toml::node* n = get(key);
    if (n == nullptr) return std::nullopt;
    const auto v = n->value<std::string>();
    if (!v || v->empty()) fail(*n, key, std::string("must be a text, e.g. ") + key + " = " + example);
    return *v;
  }
  std::optional<double> number(const std::string& key, double lo, double hi) const {
    const toml::node* n = get(key);
    if (n == nullptr) return std::nullopt;
    const auto v = n->value<double>();
    if (!v || !(*v >= lo && *v <= hi)) {
      char range[96];
      std::snprintf(range, sizeof range, "must be a number from %g to %g", lo, hi);
      fail(*n, key, range);
    }
    return *v;
  }
  std::optional<bool> boolean(const std::string& key) const {
    const toml::node* n = get(key);
    if (n == nullptr) return std::nullopt;
    if (!n->is_boolean()) fail(*n, key, "must be true or false");
    return n->value<bool>();
  }
  // A list with one entry per robot.
  template <class T>
  std::vector<T> per_robot(const std::string& key, std::size_t robots, const char* what) const {
    std::vector<T> out;
    const toml::array* a = array(key);
    if (a == nullptr) return out;
    for (const toml::node& e : *a) {
      const auto v = e.value<T>();
      if (!v) fail(e, key, std::string("must be ") + what);
      out.push_back(*v);
    }
    if (out.size() != robots) {
      fail(*get(key), key, "give one per robot: the file places " + std::to_string(robots) + " robot(s)");
    }
    return out;
  }
  /// A list of node names (can_nodes::node_by_name) as a set, from `list`
  /// (the field `key`'s value or an entry of it): no name twice, at least one.
  can_nodes::NodeSet node_set(const toml::node& list, const std::string& key) const {
    const toml::array* a = list.as_array();
    if (a == nullptr || a->empty()) {
      fail(list, key,
           "must list the nodes canhil emulates, e.g. [\"Motor1\", \"Motor2\", \"Motor3\"]; the nodes are " +
               can_nodes::node_name_list());
    }
    can_nodes::NodeSet set;
    for (const toml::node& e : *a) {
      const auto name = e.value<std::string>();
      const auto id = name ? can_nodes::node_by_name(*name) : std::nullopt;
      if (!id) fail(e, key, "not a node's name; the nodes are " + can_nodes::node_name_list());
      if (set.contains(*id)) fail(e, key, *name + " appears twice");
      set.insert(*id);
    }
    return set;
  }
  const std::string& file() const { return file_; }

 private:
  const toml::table& table_;
  std::string name_;
  const std::string& file_;
};

}  // namespace canhil::emulator
