#include "canhil/can_nodes/node_ids.hpp"

#include <cctype>

namespace canhil::can_nodes {
namespace {

// The same name, any case, a space and an underscore alike.
bool same_name(std::string_view written, std::string_view name) noexcept {
  if (written.size() != name.size()) return false;
  for (std::size_t i = 0; i < name.size(); ++i) {
    const auto a = static_cast<unsigned char>(written[i] == '_' ? ' ' : written[i]);
    const auto b = static_cast<unsigned char>(name[i] == '_' ? ' ' : name[i]);
    if (std::tolower(a) != std::tolower(b)) return false;
  }
  return true;
}

std::string written_name(NodeId id) {
  std::string name = node_name(id);
  for (char& c : name) {
    if (c == ' ') c = '_';
  }
  return name;
}

}  // namespace

std::optional<NodeId> node_by_name(std::string_view name) noexcept {
  for (std::size_t i = 0; i < kNodeCount; ++i) {
    if (same_name(name, kNodeNames[i])) return static_cast<NodeId>(i);
  }
  return std::nullopt;
}

std::string node_name_list() {
  std::string out;
  for (std::size_t i = 0; i < kNodeCount; ++i) out += (i == 0 ? "" : ", ") + written_name(static_cast<NodeId>(i));
  return out;
}

std::string describe(NodeSet set) {
  if (set.is_all()) return "all eight nodes";
  std::string out;
  for (std::size_t i = 0; i < kNodeCount; ++i) {
    const auto id = static_cast<NodeId>(i);
    if (set.contains(id)) out += (out.empty() ? "" : ", ") + written_name(id);
  }
  return out.empty() ? "no node" : out;
}

}  // namespace canhil::can_nodes
