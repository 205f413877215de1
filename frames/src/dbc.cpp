#include "canhil/frames/dbc.hpp"

#include <unistd.h>
#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <sstream>

#include "canhil/base/assets.hpp"
#include "dbc_parser.hpp"

namespace canhil::frames {

const SignalDef* MessageDef::find_signal(std::string_view signal_name) const noexcept {
  for (const auto& s : signals) {
    if (s.name == signal_name) return &s;
  }
  return nullptr;
}

std::vector<std::string> MessageDef::receivers() const {
  std::vector<std::string> out;
  for (const auto& s : signals) {
    for (const auto& r : s.receivers) {
      if (std::find(out.begin(), out.end(), r) == out.end()) out.push_back(r);
    }
  }
  return out;
}

std::optional<std::int64_t> MessageDef::attribute_int(std::string_view attr) const {
  const auto it = attributes.find(std::string(attr));
  if (it == attributes.end()) return std::nullopt;
  if (const auto* i = std::get_if<std::int64_t>(&it->second)) return *i;
  if (const auto* d = std::get_if<double>(&it->second)) return static_cast<std::int64_t>(*d);
  return std::nullopt;
}

std::optional<std::string> MessageDef::attribute_text(std::string_view attr) const {
  const auto it = attributes.find(std::string(attr));
  if (it == attributes.end()) return std::nullopt;
  if (const auto* s = std::get_if<std::string>(&it->second)) return *s;
  if (attribute_defs != nullptr) {
    for (const auto& d : *attribute_defs) {
      if (d.name == attr && d.type == AttributeType::kEnum) {
        const auto index = std::get<std::int64_t>(it->second);
        return d.enum_values.at(static_cast<std::size_t>(index));
      }
    }
  }
  return std::nullopt;
}

Database::Database(const Database& other)
    : file(other.file),
      version(other.version),
      nodes(other.nodes),
      messages(other.messages),
      attribute_defs(other.attribute_defs),
      network_attributes(other.network_attributes) {
  relink();
}

Database& Database::operator=(const Database& other) {
  if (this != &other) {
    Database copy(other);
    *this = std::move(copy);
  }
  return *this;
}

Database::Database(Database&& other) noexcept
    : file(std::move(other.file)),
      version(std::move(other.version)),
      nodes(std::move(other.nodes)),
      messages(std::move(other.messages)),
      attribute_defs(std::move(other.attribute_defs)),
      network_attributes(std::move(other.network_attributes)) {
  relink();
}

Database& Database::operator=(Database&& other) noexcept {
  file = std::move(other.file);
  version = std::move(other.version);
  nodes = std::move(other.nodes);
  messages = std::move(other.messages);
  attribute_defs = std::move(other.attribute_defs);
  network_attributes = std::move(other.network_attributes);
  relink();
  return *this;
}

void Database::relink() noexcept {
  for (auto& m : messages) m.attribute_defs = &attribute_defs;
}

const MessageDef* Database::find_message(std::string_view message_name) const noexcept {
  for (const auto& m : messages) {
    if (m.name == message_name) return &m;
  }
  return nullptr;
}

const MessageDef* Database::find_message(std::uint32_t id, bool extended) const noexcept {
  for (const auto& m : messages) {
    if (m.id == id && m.extended == extended) return &m;
  }
  return nullptr;
}

std::optional<std::uint32_t> Database::baudrate() const noexcept {
  const auto it = network_attributes.find("Baudrate");
  if (it == network_attributes.end()) return std::nullopt;
  const auto* v = std::get_if<std::int64_t>(&it->second);
  if (v == nullptr || *v <= 0 || *v > 0xFFFF'FFFF) return std::nullopt;
  return static_cast<std::uint32_t>(*v);
}

Database parse_dbc(std::string_view text, std::string_view file_name) {
  dbc_detail::Parser parser(text, std::string(file_name));
  Database db = parser.parse();
  db.relink();
  return db;
}

Database load_dbc(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    throw DbcError(path.string(), 0,
                   "cannot read the DBC file (does it exist?); pass an existing file with --dbc FILE");
  }
  std::ostringstream buf;
  buf << in.rdbuf();
  return parse_dbc(buf.str(), path.string());
}

std::filesystem::path default_dbc_path() {
  if (auto given = path_from_environment("CANHIL_DBC")) return *given;
  return installed_or_built({"canhil.dbc", "../share/canhil/canhil.dbc"}, CANHIL_SOURCE_DBC);
}

}  // namespace canhil::frames
