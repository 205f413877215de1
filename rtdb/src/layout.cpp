// Layouts after loading: looking items and quantities up, the checks users
// call (require, check_size), where the shipped files are, and ItemBuffer's
// conversions between SI and the stored bytes (allocation-free).
#include "canhil/rtdb/layout.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>

#include "canhil/base/assets.hpp"
#include "canhil/base/demand.hpp"
#include "layout_internal.hpp"

static_assert(std::endian::native == std::endian::little, "layouts describe little-endian items");

namespace canhil::rtdb {
namespace {

constexpr std::array<std::string_view, 2> kShipped{"cambada", "canhil"};

template <class T>
T saturate(double v) noexcept {
  if (std::isnan(v)) return T{0};
  // The bounds as doubles: exact for every type up to 32 bits; for 64 bits
  // 2^63 and 2^64, the first values past the range.
  constexpr double lo = static_cast<double>(std::numeric_limits<T>::min());
  constexpr double past_hi = static_cast<double>(std::numeric_limits<T>::max()) + 1.0;
  if (v <= lo) return std::numeric_limits<T>::min();
  if (v >= past_hi) return std::numeric_limits<T>::max();
  return static_cast<T>(v);
}

template <class T>
void put(std::byte* at, T v) noexcept {
  std::memcpy(at, &v, sizeof v);
}

template <class T>
T take(const std::byte* at) noexcept {
  T v;
  std::memcpy(&v, at, sizeof v);
  return v;
}

// Stores v (already in the stored unit, rounded for integers) as `type`.
void store(std::byte* at, ScalarType type, double v) noexcept {
  switch (type) {
    case ScalarType::kI8:
      put(at, saturate<std::int8_t>(v));
      break;
    case ScalarType::kU8:
      put(at, saturate<std::uint8_t>(v));
      break;
    case ScalarType::kI16:
      put(at, saturate<std::int16_t>(v));
      break;
    case ScalarType::kU16:
      put(at, saturate<std::uint16_t>(v));
      break;
    case ScalarType::kI32:
      put(at, saturate<std::int32_t>(v));
      break;
    case ScalarType::kU32:
      put(at, saturate<std::uint32_t>(v));
      break;
    case ScalarType::kI64:
      put(at, saturate<std::int64_t>(v));
      break;
    case ScalarType::kU64:
      put(at, saturate<std::uint64_t>(v));
      break;
    case ScalarType::kF32: {
      constexpr double kMax = std::numeric_limits<float>::max();
      put(at, static_cast<float>(std::isfinite(v) ? std::clamp(v, -kMax, kMax) : v));
      break;
    }
    case ScalarType::kF64:
      put(at, v);
      break;
    case ScalarType::kBool:
      put(at, static_cast<std::uint8_t>(v != 0 && !std::isnan(v) ? 1 : 0));
      break;
  }
}

double load(const std::byte* at, ScalarType type) noexcept {
  switch (type) {
    case ScalarType::kI8:
      return take<std::int8_t>(at);
    case ScalarType::kU8:
      return take<std::uint8_t>(at);
    case ScalarType::kI16:
      return take<std::int16_t>(at);
    case ScalarType::kU16:
      return take<std::uint16_t>(at);
    case ScalarType::kI32:
      return take<std::int32_t>(at);
    case ScalarType::kU32:
      return take<std::uint32_t>(at);
    case ScalarType::kI64:
      return static_cast<double>(take<std::int64_t>(at));
    case ScalarType::kU64:
      return static_cast<double>(take<std::uint64_t>(at));
    case ScalarType::kF32:
      return take<float>(at);
    case ScalarType::kF64:
      return take<double>(at);
    case ScalarType::kBool:
      return take<std::uint8_t>(at) != 0 ? 1.0 : 0.0;
  }
  return 0;
}

// Into [low, low + turn).
double wrap_into(double v, double low, double turn) noexcept {
  double r = v - turn * std::floor((v - low) / turn);
  if (r >= low + turn) r -= turn;
  if (r < low) r = low;
  return r;
}

// SI -> the stored unit, before the cast: scale and direction, add, wrap, round.
double to_stored(const FieldLayout& f, double si) noexcept {
  double v = si * f.stored_per_si;
  if (f.add != 0) v += f.add;  // not -0.0 + 0: a float field keeps the sign of zero as a cast would
  const double low = f.wrap == Wrap::kHalfTurns ? -f.turn / 2 : 0.0;
  if (f.turn > 0) v = wrap_into(v, low, f.turn);
  if (is_integer(f.type)) {
    v = f.rounding == Rounding::kNearest ? std::round(v) : std::trunc(v);
    if (f.turn > 0 && (v >= low + f.turn || v < low)) v = std::round(wrap_into(v, low, f.turn));
  }
  return v;
}

double to_si(const FieldLayout& f, double stored) noexcept {
  return (f.add != 0 ? stored - f.add : stored) / f.stored_per_si;
}

// The element index an (agent) index addresses, or count when none.
std::size_t element(const FieldLayout& f, std::size_t index) noexcept {
  if (f.by_agent) {
    const auto base = static_cast<std::size_t>(f.index_base);
    return index < base ? f.count : std::min(index - base, f.count);
  }
  return std::min(index, f.count);
}

std::size_t at_byte(const FieldLayout& f, std::size_t e, std::size_t component) noexcept {
  return f.offset_bytes + e * f.stride_bytes + component * size_of(f.type);
}

}  // namespace

std::size_t size_of(ScalarType type) noexcept {
  switch (type) {
    case ScalarType::kI8:
    case ScalarType::kU8:
    case ScalarType::kBool:
      return 1;
    case ScalarType::kI16:
    case ScalarType::kU16:
      return 2;
    case ScalarType::kI32:
    case ScalarType::kU32:
    case ScalarType::kF32:
      return 4;
    case ScalarType::kI64:
    case ScalarType::kU64:
    case ScalarType::kF64:
      return 8;
  }
  return 1;
}

std::string_view name_of(ScalarType type) noexcept {
  constexpr std::array<std::string_view, 11> kNames{"i8",  "u8",  "i16", "u16", "i32", "u32",
                                                    "i64", "u64", "f32", "f64", "bool"};
  return kNames[static_cast<std::size_t>(type)];
}

// ---- Quantity, ItemLayout, Layout ----

std::string_view Quantity::name() const noexcept { return binding_ == nullptr ? "" : binding_->info->name; }
QuantityKind Quantity::kind() const noexcept {
  return binding_ == nullptr ? QuantityKind::kNumber : binding_->info->kind;
}

const FieldLayout* ItemLayout::field(std::string_view c_name) const noexcept {
  for (const FieldLayout& f : fields_) {
    if (f.name == c_name) return &f;
  }
  return nullptr;
}

Quantity ItemLayout::quantity(std::string_view name) const {
  for (const detail::Binding& b : bindings_) {
    if (b.info->name == name) return Quantity(&b);
  }
  CANHIL_DEMAND(!is_contract_item(name_) || find_quantity(name_, name) != nullptr,
                "a quantity outside canhil's contract for this item (see rtdb/src/layout_contract.cpp)");
  return {};
}

bool ItemLayout::has(std::string_view quantity) const noexcept { return capacity(quantity) != 0; }

std::size_t ItemLayout::capacity(std::string_view quantity) const noexcept {
  for (const detail::Binding& b : bindings_) {
    if (b.info->name == quantity) return b.capacity;
  }
  return 0;
}

std::vector<std::string_view> ItemLayout::quantities() const {
  std::vector<std::string_view> out;
  for (const detail::Binding& b : bindings_) out.push_back(b.info->name);
  return out;
}

ItemLayout LayoutBuilder::make_item(std::string name, std::size_t size_bytes, std::string file, int line,
                                    DeltasFrame frame, std::vector<FieldLayout> fields) {
  ItemLayout item;
  item.name_ = std::move(name);
  item.size_bytes_ = size_bytes;
  item.file_ = std::move(file);
  item.line_ = line;
  item.deltas_frame_ = frame;
  item.fields_ = std::move(fields);
  for (const QuantityInfo& q : quantities_of(item.name_)) {
    detail::Binding b;
    b.info = &q;
    b.capacity = std::numeric_limits<std::size_t>::max();
    for (std::size_t i = 0; i < item.fields_.size(); ++i) {
      if (item.fields_[i].quantity != q.name) continue;
      b.fields.push_back(i);
      b.capacity = std::min(b.capacity, q.kind == QuantityKind::kPoints || q.per_agent ? item.fields_[i].count : 1);
    }
    if (!b.fields.empty()) item.bindings_.push_back(std::move(b));
  }
  for (detail::Binding& b : item.bindings_) {
    if (b.info->kind != QuantityKind::kPoints) continue;
    const std::string count_name = std::string(b.info->name) + ".count";
    for (std::size_t i = 0; i < item.bindings_.size(); ++i) {
      if (item.bindings_[i].info->name == count_name) b.count = i;
    }
  }
  return item;
}

Layout LayoutBuilder::make_layout(Layout::Data data) {
  return Layout(std::make_shared<const Layout::Data>(std::move(data)));
}

const std::string& Layout::name() const noexcept { return data_->name; }
const std::string& Layout::description() const noexcept { return data_->description; }
const std::string& Layout::file() const noexcept { return data_->file; }

const ItemLayout* Layout::item(std::string_view name) const noexcept {
  for (const ItemLayout& i : data_->items) {
    if (i.name() == name) return &i;
  }
  return nullptr;
}

std::vector<std::string> Layout::items() const {
  std::vector<std::string> out;
  for (const ItemLayout& i : data_->items) out.push_back(i.name());
  return out;
}

std::span<const std::string_view> Layout::shipped_names() noexcept { return kShipped; }

std::filesystem::path Layout::shipped_path(std::string_view name) {
  namespace fs = std::filesystem;
  if (std::find(kShipped.begin(), kShipped.end(), name) == kShipped.end()) {
    throw LayoutError(std::string(name), 0, "",
                      "no layout of that name ships with canhil; the shipped layouts are cambada (the public "
                      "CAMBADA structs) and canhil (canhil's own); or give your description file's path");
  }
  const std::string file = std::string(name) + ".toml";
  if (auto dir = path_from_environment("CANHIL_LAYOUT_DIR")) return *dir / file;
  return installed_or_built({fs::path("../share/canhil/layouts") / file}, fs::path(CANHIL_SOURCE_LAYOUTS) / file);
}

Layout Layout::shipped(std::string_view name) { return load(shipped_path(name)); }

const ItemLayout& require(const Layout& layout, std::string_view item,
                          std::initializer_list<std::string_view> quantities) {
  const ItemLayout* it = layout.item(item);
  if (it == nullptr) {
    std::string wanted;
    for (std::string_view q : quantities) wanted += (wanted.empty() ? "" : ", ") + std::string(q);
    throw LayoutError(layout.file(), 0, std::string(item),
                      "layout " + layout.name() + " does not describe this item, and canhil needs it" +
                          (wanted.empty() ? "" : " (for " + wanted + ")") + "; add a table [" + std::string(item) +
                          "] with its size and fields (docs/layouts.md)");
  }
  for (std::string_view q : quantities) {
    const QuantityInfo* info = find_quantity(item, q);
    CANHIL_DEMAND(info != nullptr, "require() asked for a quantity outside canhil's contract");
    if (it->has(q)) continue;
    throw LayoutError(layout.file(), it->line(), std::string(item) + "." + std::string(q),
                      "layout " + layout.name() + " has no field for this quantity (" + std::string(info->meaning) +
                          ") and canhil needs it; add a field with from = \"" + std::string(q) + "\" to [" +
                          std::string(item) + "]");
  }
  return *it;
}

void check_size(const Layout& layout, const ItemLayout& item, std::size_t rtdb_item_bytes) {
  if (item.size_bytes() == rtdb_item_bytes) return;
  throw LayoutError(layout.file(), item.line(), item.name(),
                    "the RTDB's item is " + std::to_string(rtdb_item_bytes) + " bytes but layout " + layout.name() +
                        " says size = " + std::to_string(item.size_bytes()) +
                        "; use the layout that matches this RTDB's structs, or correct the description");
}

// ---- ItemBuffer ----

ItemBuffer::ItemBuffer(const ItemLayout& item) : item_(&item), bytes_(item.size_bytes()) { clear(); }

void ItemBuffer::clear() noexcept {
  std::fill(bytes_.begin(), bytes_.end(), std::byte{0});
  for (const FieldLayout& f : item_->fields()) {
    if (!f.value) continue;
    for (std::size_t e = 0; e < f.count; ++e) {
      for (std::size_t c = 0; c < f.components; ++c) store(&bytes_[at_byte(f, e, c)], f.type, *f.value);
    }
  }
}

void ItemBuffer::set(Quantity q, double si, std::size_t index) noexcept {
  if (!q) return;
  CANHIL_DEMAND(q.kind() != QuantityKind::kPoints, "a point list is written with set_points");
  const auto fields = item_->fields();
  for (std::size_t i : q.binding_->fields) {
    const FieldLayout& f = fields[i];
    const std::size_t e = element(f, index);
    if (e >= f.count) continue;
    std::byte* at = &bytes_[at_byte(f, e, 0)];
    if (q.kind() == QuantityKind::kBool) {
      const bool on = si != 0 && !std::isnan(si);
      store(at, f.type, f.type == ScalarType::kBool ? (on ? 1.0 : 0.0) : (on ? f.true_value : f.false_value));
    } else {
      store(at, f.type, to_stored(f, si));
    }
  }
}

void ItemBuffer::set(Quantity q, std::string_view name, std::size_t index) {
  if (!q) return;
  CANHIL_DEMAND(q.kind() == QuantityKind::kEnum, "set(quantity, name) is for enum quantities");
  const auto fields = item_->fields();
  for (std::size_t i : q.binding_->fields) {  // every field knows the name, or nothing is written
    const FieldLayout& f = fields[i];
    if (std::any_of(f.values.begin(), f.values.end(), [&](const EnumValue& v) { return v.name == name; })) continue;
    std::string given;
    for (const EnumValue& v : f.values) given += (given.empty() ? "" : ", ") + v.name;
    throw LayoutError(item_->file(), f.line, item_->name() + "." + f.name,
                      "no value for " + std::string(q.name()) + " '" + std::string(name) + "' (this field gives " +
                          given + "); add " + std::string(name) + " = <integer> to its values");
  }
  for (std::size_t i : q.binding_->fields) {
    const FieldLayout& f = fields[i];
    const std::size_t e = element(f, index);
    if (e >= f.count) continue;
    for (const EnumValue& v : f.values) {
      if (v.name == name) store(&bytes_[at_byte(f, e, 0)], f.type, static_cast<double>(v.value));
    }
  }
}

void ItemBuffer::set_points(Quantity list, std::span<const std::array<double, 2>> points) noexcept {
  if (!list) return;
  CANHIL_DEMAND(list.kind() == QuantityKind::kPoints, "set_points is for point lists");
  const std::size_t n = std::min(points.size(), list.binding_->capacity);
  const auto fields = item_->fields();
  for (std::size_t i : list.binding_->fields) {
    const FieldLayout& f = fields[i];
    if (f.type == ScalarType::kF32 && f.stored_per_si == 1.0 && f.add == 0 && f.turn <= 0) {
      // Metres as floats (canhil's and CAMBADA's vision): what store(to_stored()) does, without its cases.
      static constexpr double kMax = std::numeric_limits<float>::max();
      const auto to_float = [](double v) {
        return static_cast<float>(std::isfinite(v) ? std::clamp(v, -kMax, kMax) : v);
      };
      // x then y, side by side (at_byte(f, p, 1) = at_byte(f, p, 0) + 4): one 8-byte copy a point.
      std::byte* at = bytes_.data() + at_byte(f, 0, 0);
      // Within float's range, the usual case, to_float is the plain conversion
      // (a NaN is passed on either way: std::max leaves it out of `largest`).
      double largest = 0;
      for (std::size_t p = 0; p < n; ++p) {
        largest = std::max(largest, std::max(std::fabs(points[p][0]), std::fabs(points[p][1])));
      }
      if (largest <= kMax) {
        for (std::size_t p = 0; p < n; ++p, at += f.stride_bytes) {
          const std::array<float, 2> xy{static_cast<float>(points[p][0]), static_cast<float>(points[p][1])};
          std::memcpy(at, xy.data(), sizeof xy);
        }
        continue;
      }
      for (std::size_t p = 0; p < n; ++p, at += f.stride_bytes) {
        const std::array<float, 2> xy{to_float(points[p][0]), to_float(points[p][1])};
        std::memcpy(at, xy.data(), sizeof xy);
      }
      continue;
    }
    for (std::size_t p = 0; p < n; ++p) {
      store(&bytes_[at_byte(f, p, 0)], f.type, to_stored(f, points[p][0]));
      store(&bytes_[at_byte(f, p, 1)], f.type, to_stored(f, points[p][1]));
    }
  }
  if (list.binding_->count != detail::Binding::kNone) {
    set(Quantity(&item_->bindings_[list.binding_->count]), static_cast<double>(n));
  }
}

void ItemBuffer::replace_points(Quantity list, std::span<const std::array<double, 2>> points,
                                std::vector<ByteRange>* changed) noexcept {
  if (!list) return;
  CANHIL_DEMAND(list.kind() == QuantityKind::kPoints, "replace_points is for point lists");
  const std::size_t capacity = list.binding_->capacity;
  std::size_t held = capacity;
  const bool counted = list.binding_->count != detail::Binding::kNone;
  if (counted) {
    const double n = get(Quantity(&item_->bindings_[list.binding_->count]));
    held = n > 0 ? std::min(capacity, static_cast<std::size_t>(n)) : 0;
  }
  const std::size_t keep = std::min(points.size(), capacity);  // overwritten by set_points
  const auto fields = item_->fields();
  for (std::size_t i : list.binding_->fields) {
    const FieldLayout& f = fields[i];
    for (std::size_t e = keep; e < held && e < f.count; ++e) {
      if (f.value) {
        for (std::size_t c = 0; c < f.components; ++c) store(&bytes_[at_byte(f, e, c)], f.type, *f.value);
      } else {
        std::memset(&bytes_[at_byte(f, e, 0)], 0, f.element_bytes());
      }
    }
    const std::size_t touched = std::min(std::max(keep, held), f.count);
    if (changed != nullptr && touched > 0) {
      changed->push_back({at_byte(f, 0, 0), (touched - 1) * f.stride_bytes + f.element_bytes()});
    }
  }
  set_points(list, points);
  if (changed != nullptr && counted) {
    for (std::size_t i : item_->bindings_[list.binding_->count].fields) {
      const FieldLayout& f = fields[i];
      changed->push_back({f.offset_bytes, f.end_bytes() - f.offset_bytes});
    }
  }
}

double ItemBuffer::get(Quantity q, std::size_t index) const noexcept {
  if (!q) return 0;
  CANHIL_DEMAND(q.kind() != QuantityKind::kPoints, "a point list is read with get_point");
  const FieldLayout& f = item_->fields()[q.binding_->fields.front()];
  const std::size_t e = element(f, index);
  if (e >= f.count) return 0;
  const double raw = load(&bytes_[at_byte(f, e, 0)], f.type);
  if (q.kind() == QuantityKind::kBool) {
    return (f.type == ScalarType::kBool ? raw != 0 : raw != f.false_value) ? 1.0 : 0.0;
  }
  return to_si(f, raw);
}

std::string_view ItemBuffer::get_enum(Quantity q, std::size_t index) const noexcept {
  if (!q || q.kind() != QuantityKind::kEnum) return "";
  const FieldLayout& f = item_->fields()[q.binding_->fields.front()];
  const std::size_t e = element(f, index);
  if (e >= f.count) return "";
  const double raw = load(&bytes_[at_byte(f, e, 0)], f.type);
  for (const EnumValue& v : f.values) {
    if (static_cast<double>(v.value) == raw) return v.name;
  }
  return "";
}

std::array<double, 2> ItemBuffer::get_point(Quantity list, std::size_t i) const noexcept {
  if (!list || list.kind() != QuantityKind::kPoints) return {0, 0};
  const FieldLayout& f = item_->fields()[list.binding_->fields.front()];
  if (i >= f.count) return {0, 0};
  return {to_si(f, load(&bytes_[at_byte(f, i, 0)], f.type)), to_si(f, load(&bytes_[at_byte(f, i, 1)], f.type))};
}

}  // namespace canhil::rtdb
