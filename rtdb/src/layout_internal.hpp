// Inside the layout library: the units, the shared data of a Layout and the
// builder the parser fills it through.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "canhil/rtdb/layout.hpp"

namespace canhil::rtdb {

/// What a quantity (or a unit) measures; a field's unit must fit its quantity.
enum class Dimension : std::uint8_t { kNone, kLength, kAngle, kSpeed, kAngularSpeed, kVoltage, kTime };

/// A stored unit: how many of it make one SI unit of its dimension,
/// `factor × π^pi_power` (kept apart so that deg -> cdeg is exactly 100).
struct UnitInfo {
  std::string_view name;
  Dimension dimension;
  double factor;
  int pi_power;
};

const UnitInfo* find_unit(std::string_view name) noexcept;
std::span<const UnitInfo> units() noexcept;
std::string_view dimension_name(Dimension d) noexcept;   ///< "a length", ...
std::string units_of(Dimension d);                       ///< "m, cm, mm"
Dimension dimension_of(const QuantityInfo& q) noexcept;  ///< from its SI unit
/// Stored units per unit of the quantity: e.g. 1000 for mm against m, exactly 100 for cdeg against deg.
double units_per(const UnitInfo& stored, const UnitInfo& given) noexcept;
/// The contract's quantities of one item (empty for an item outside it).
std::span<const QuantityInfo> quantities_of(std::string_view item) noexcept;
bool is_contract_item(std::string_view item) noexcept;
std::span<const std::string_view> contract_items() noexcept;

/// A whole-number type (not f32, f64 or bool).
inline bool is_integer(ScalarType t) noexcept {
  return t != ScalarType::kF32 && t != ScalarType::kF64 && t != ScalarType::kBool;
}

/// ` did you mean X?` for the nearest candidate within distance 3, or "".
std::string did_you_mean(std::string_view word, std::span<const std::string_view> candidates);

struct Layout::Data {
  std::string name;
  std::string description;
  std::string file;
  std::vector<ItemLayout> items;  // in file order
};

/// Fills a Layout (the parser's side door into the private parts).
struct LayoutBuilder {
  /// Binds the fields' quantities (checked by the parser) to handles.
  static ItemLayout make_item(std::string name, std::size_t size_bytes, std::string file, int line, DeltasFrame frame,
                              std::vector<FieldLayout> fields);
  static Layout make_layout(Layout::Data data);
};

}  // namespace canhil::rtdb
