// canhil/frames/dbc.hpp — the message set as a DBC database, loaded at run time.
//
// A team whose firmware lays frames out differently edits the DBC file, not
// the code. The parser reads the subset of the Vector DBC format that CAN
// databases use in practice (VERSION, NS_, BS_, BU_, BO_, SG_, CM_, BA_DEF_,
// BA_DEF_DEF_, BA_, VAL_, VAL_TABLE_, SIG_VALTYPE_, BO_TX_BU_; other sections
// are skipped) and checks what a codec relies on. Every mistake is reported as
// a DbcError whose text is `FILE:LINE: what is wrong; what to do`.
//
// Not supported (reported as an error, never misread): multiplexed signals,
// CAN FD lengths (> 8 bytes).
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <variant>
#include <vector>

#include "canhil/base/located_error.hpp"

namespace canhil::frames {

/// A mistake in a DBC file: `FILE:LINE: what is wrong; what to do` (no field).
class DbcError : public LocatedError {
 public:
  DbcError(std::string file, int line, const std::string& message) : LocatedError(std::move(file), line, "", message) {}
};

enum class ByteOrder : std::uint8_t { kIntel, kMotorola };
enum class ValueType : std::uint8_t { kUnsigned, kSigned, kFloat32, kFloat64 };

/// An attribute value: integers (INT, HEX and ENUM as its index), floats, strings.
using AttributeValue = std::variant<std::int64_t, double, std::string>;

enum class AttributeScope : std::uint8_t { kNetwork, kNode, kMessage, kSignal, kEnvironment };
enum class AttributeType : std::uint8_t { kInt, kHex, kFloat, kString, kEnum };

struct AttributeDef {
  std::string name;
  AttributeScope scope = AttributeScope::kNetwork;
  AttributeType type = AttributeType::kInt;
  double minimum = 0;
  double maximum = 0;
  std::vector<std::string> enum_values;
  std::optional<AttributeValue> default_value;
  int line = 0;
};

struct SignalDef {
  std::string name;
  std::uint16_t start_bit = 0;  ///< as written in the DBC (Motorola: the MSB's position)
  std::uint16_t length = 0;     ///< bits, 1..64
  ByteOrder byte_order = ByteOrder::kIntel;
  ValueType value_type = ValueType::kUnsigned;
  double factor = 1.0;
  double offset = 0.0;
  double minimum = 0.0;  ///< physical; minimum == maximum == 0 means "no range given"
  double maximum = 0.0;
  std::string unit;
  std::vector<std::string> receivers;
  std::string comment;
  std::map<std::int64_t, std::string> value_names;  ///< VAL_ raw value -> description
  std::map<std::string, AttributeValue> attributes;
  int line = 0;

  bool has_range() const noexcept { return minimum != 0.0 || maximum != 0.0; }
};

struct MessageDef {
  std::string name;
  std::uint32_t id = 0;
  bool extended = false;
  std::uint8_t length = 0;  ///< bytes, 0..8
  std::string transmitter;
  std::vector<std::string> extra_transmitters;  ///< BO_TX_BU_
  std::vector<SignalDef> signals;
  std::string comment;
  /// Every message-scope attribute, with the definition's default filled in.
  std::map<std::string, AttributeValue> attributes;
  int line = 0;

  const SignalDef* find_signal(std::string_view signal_name) const noexcept;
  /// Receivers of any signal, in first-seen order.
  std::vector<std::string> receivers() const;
  /// The attribute as an integer (INT, HEX, ENUM index, FLOAT truncated); nullopt if absent.
  std::optional<std::int64_t> attribute_int(std::string_view attr) const;
  /// ENUM attributes as their text, STRING as is; nullopt if absent or numeric.
  std::optional<std::string> attribute_text(std::string_view attr) const;
  /// Back-pointer set by the parser, for attribute_text on ENUMs.
  const std::vector<AttributeDef>* attribute_defs = nullptr;
};

struct Database {
  std::string file;  ///< where it was loaded from (for messages)
  std::string version;
  std::vector<std::string> nodes;
  std::vector<MessageDef> messages;
  std::vector<AttributeDef> attribute_defs;
  std::map<std::string, AttributeValue> network_attributes;

  Database() = default;
  Database(const Database& other);
  Database& operator=(const Database& other);
  Database(Database&&) noexcept;
  Database& operator=(Database&&) noexcept;
  ~Database() = default;

  const MessageDef* find_message(std::string_view message_name) const noexcept;
  const MessageDef* find_message(std::uint32_t id, bool extended) const noexcept;
  /// The bus's bit rate: the network attribute "Baudrate" (an INT, bit/s),
  /// nullopt when absent or not positive.
  std::optional<std::uint32_t> baudrate() const noexcept;

 private:
  void relink() noexcept;
  friend Database parse_dbc(std::string_view, std::string_view);
};

/// Parses DBC text; `file_name` is used in error messages only.
Database parse_dbc(std::string_view text, std::string_view file_name);
/// Reads and parses a DBC file. Throws DbcError (also for a file that cannot be read).
Database load_dbc(const std::filesystem::path& path);

/// The message set shipped with canhil (found next to the executable, in the
/// source tree or in the install prefix; CANHIL_DBC in the environment wins).
std::filesystem::path default_dbc_path();

}  // namespace canhil::frames
