// Reading a layout description (TOML) and checking it: every mistake is a
// LayoutError `FILE:LINE: ITEM.FIELD: what is wrong; what to do`.
#include <toml++/toml.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <numbers>
#include <optional>
#include <regex>
#include <sstream>

#include "layout_internal.hpp"

namespace canhil::rtdb {
namespace {

constexpr std::int64_t kMaxItemBytes = std::int64_t{1} << 24;

constexpr std::array<std::pair<std::string_view, ScalarType>, 11> kTypes{{{"i8", ScalarType::kI8},
                                                                          {"u8", ScalarType::kU8},
                                                                          {"i16", ScalarType::kI16},
                                                                          {"u16", ScalarType::kU16},
                                                                          {"i32", ScalarType::kI32},
                                                                          {"u32", ScalarType::kU32},
                                                                          {"i64", ScalarType::kI64},
                                                                          {"u64", ScalarType::kU64},
                                                                          {"f32", ScalarType::kF32},
                                                                          {"f64", ScalarType::kF64},
                                                                          {"bool", ScalarType::kBool}}};

constexpr std::array<std::string_view, 18> kFieldKeys{"type",  "offset", "count", "stride", "components", "from",
                                                      "value", "unit",   "scale", "add",    "direction",  "wrap",
                                                      "round", "true",   "false", "values", "index",      "index_base"};
// Keys that say how a quantity is stored: meaningless without `from`.
constexpr std::array<std::string_view, 11> kConversionKeys{"unit", "scale", "add",    "direction", "wrap",      "round",
                                                           "true", "false", "values", "index",     "index_base"};
constexpr std::array<std::string_view, 2> kLayoutKeys{"name", "description"};

int line_of(const toml::node& n) { return static_cast<int>(n.source().begin.line); }

std::pair<double, double> range_of(ScalarType t) {
  switch (t) {
    case ScalarType::kI8:
      return {-128, 127};
    case ScalarType::kU8:
      return {0, 255};
    case ScalarType::kI16:
      return {-32768, 32767};
    case ScalarType::kU16:
      return {0, 65535};
    case ScalarType::kI32:
      return {-2147483648.0, 2147483647.0};
    case ScalarType::kU32:
      return {0, 4294967295.0};
    case ScalarType::kI64:
      return {-9223372036854775808.0, 9223372036854775807.0};
    case ScalarType::kU64:
      return {0, 18446744073709551615.0};
    case ScalarType::kBool:
      return {0, 1};
    case ScalarType::kF32:
    case ScalarType::kF64:
      break;
  }
  return {-std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity()};
}

std::string join(std::span<const std::string_view> words) {
  std::string out;
  for (std::string_view w : words) out += (out.empty() ? "" : ", ") + std::string(w);
  return out;
}

// Reads the keys of one table (reject_unknown first), failing with its place.
class Reader {
 public:
  Reader(const toml::table& table, const std::string& file, std::string where, int line)
      : table_(table), file_(file), where_(std::move(where)), line_(line) {}

  [[noreturn]] void fail(const toml::node* at, const std::string& message) const {
    throw LayoutError(file_, at != nullptr ? line_of(*at) : line_, where_, message);
  }
  [[noreturn]] void fail(const std::string& key, const std::string& message) const { fail(table_.get(key), message); }
  const std::string& where() const { return where_; }
  int line() const { return line_; }
  bool has(const std::string& key) const { return table_.get(key) != nullptr; }

  std::optional<std::string> text(const std::string& key) {
    const toml::node* n = node(key);
    if (n == nullptr) return std::nullopt;
    if (const auto* s = n->as_string()) return s->get();
    fail(n, key + " must be a string in quotes");
  }
  std::optional<std::int64_t> integer(const std::string& key, std::int64_t min, std::int64_t max) {
    const toml::node* n = node(key);
    if (n == nullptr) return std::nullopt;
    const auto* i = n->as_integer();
    if (i == nullptr) fail(n, key + " must be a whole number");
    if (i->get() < min || i->get() > max) {
      fail(n, key + " must be " +
                  (max == std::numeric_limits<std::int64_t>::max()
                       ? "at least " + std::to_string(min)
                       : "between " + std::to_string(min) + " and " + std::to_string(max)) +
                  ", got " + std::to_string(i->get()));
    }
    return i->get();
  }
  std::optional<double> number(const std::string& key) {
    const toml::node* n = node(key);
    if (n == nullptr) return std::nullopt;
    std::optional<double> v;
    if (const auto* f = n->as_floating_point()) v = f->get();
    if (const auto* i = n->as_integer()) v = static_cast<double>(i->get());
    if (!v || !std::isfinite(*v)) fail(n, key + " must be a finite number");
    return v;
  }
  std::optional<bool> boolean(const std::string& key) {
    const toml::node* n = node(key);
    if (n == nullptr) return std::nullopt;
    if (const auto* b = n->as_boolean()) return b->get();
    fail(n, key + " must be true or false");
  }
  const toml::node* node(const std::string& key) const { return table_.get(key); }
  // Before reading: a key outside `allowed` is an error (with the nearest one).
  void reject_unknown(std::span<const std::string_view> allowed, const std::string& what) const {
    for (const auto& [k, v] : table_) {
      if (std::find(allowed.begin(), allowed.end(), k.str()) != allowed.end()) continue;
      fail(&v, "unknown key " + std::string(k.str()) + ";" + did_you_mean(k.str(), allowed) + " " + what + " take " +
                   join(allowed));
    }
  }

 private:
  const toml::table& table_;
  const std::string& file_;
  std::string where_;
  int line_;
};

[[noreturn]] void unknown_quantity(Reader& r, const std::string& item, const std::string& from) {
  const toml::node* at = r.node("from");
  if (!is_contract_item(item)) {
    r.fail(at, "unknown quantity " + from + ": canhil reads and writes no quantity in " + item +
                   "; remove from (use value for a constant, or nothing for zeros)." +
                   did_you_mean(item, contract_items()) + " The items canhil uses are " + join(contract_items()));
  }
  std::vector<std::string_view> names;
  for (const QuantityInfo& q : quantities_of(item)) names.push_back(q.name);
  std::string elsewhere;
  for (const QuantityInfo& q : contract()) {
    if (q.name == from && elsewhere.empty()) elsewhere = " (" + from + " is a quantity of " + std::string(q.item) + ")";
  }
  r.fail(at, "unknown quantity " + from + elsewhere + ";" + did_you_mean(from, names) + " " + item +
                 "'s quantities are " + (names.empty() ? "none (give value or nothing)" : join(names)));
}

// What a quantity of its kind may be stored as.
void check_shape(Reader& r, const QuantityInfo& q, const FieldLayout& f) {
  const std::string what = std::string(q.name) + " ";
  if (q.kind == QuantityKind::kPoints) {
    if (f.components != 2) r.fail(nullptr, what + "is a list of (x, y) points: give components = 2");
    if (f.type == ScalarType::kBool) r.fail("type", what + "is a list of points: use a number type");
  } else if (f.components != 1) {
    r.fail("components", what + "is one value per element: components must be 1");
  }
  if (!q.per_agent && q.kind != QuantityKind::kPoints && f.count != 1) {
    r.fail("count", what + "is a single value: count must be 1");
  }
  if ((q.kind == QuantityKind::kEnum || q.kind == QuantityKind::kCount) && !is_integer(f.type)) {
    r.fail("type", what + "is stored as a whole number: use an integer type");
  }
  if (q.kind == QuantityKind::kNumber && f.type == ScalarType::kBool) {
    r.fail("type", what + "is a number: use a number type, not bool");
  }
}

// Unit, scale, add, direction, wrap, rounding; then the derived conversion.
void read_conversion(Reader& r, const QuantityInfo& q, FieldLayout& f) {
  const std::string what = std::string(q.name) + " ";
  const Dimension dim = dimension_of(q);
  const bool angular = dim == Dimension::kAngle || dim == Dimension::kAngularSpeed;
  const bool numeric = q.kind == QuantityKind::kNumber || q.kind == QuantityKind::kPoints;
  const UnitInfo* given = find_unit(q.si_unit);
  const UnitInfo* stored = given;
  if (const auto unit = r.text("unit")) {
    stored = find_unit(*unit);
    if (stored == nullptr) {
      std::vector<std::string_view> names;
      for (const UnitInfo& u : units()) names.push_back(u.name);
      r.fail("unit", "unknown unit " + *unit + ";" + did_you_mean(*unit, names) + " the units are " + join(names));
    }
    if (stored->dimension != dim) {
      r.fail("unit", "unit " + *unit + " is " + std::string(dimension_name(stored->dimension)) + " but " +
                         std::string(q.name) + " is " + std::string(dimension_name(dim)) + "; use one of " +
                         units_of(dim));
    }
  } else if (dim != Dimension::kNone) {
    r.fail(nullptr, "missing unit; " + std::string(q.name) + " is " + std::string(dimension_name(dim)) +
                        ": give the stored unit, one of " + units_of(dim));
  }
  f.unit = std::string(stored->name);
  if (const auto scale = r.number("scale")) {
    if (!numeric) r.fail("scale", "scale applies to numbers, not to " + std::string(q.name));
    if (*scale == 0) r.fail("scale", "scale must not be 0");
    f.scale = *scale;
  }
  if (const auto add = r.number("add")) {
    if (!numeric) r.fail("add", "add applies to numbers, not to " + std::string(q.name));
    f.add = *add;
  }
  const Direction native = q.clockwise ? Direction::kCw : Direction::kCcw;
  f.direction = native;
  if (const auto dir = r.text("direction")) {
    if (!angular) r.fail("direction", "direction applies to angles and angular speeds; " + what + "is neither");
    if (*dir != "ccw" && *dir != "cw") r.fail("direction", "direction must be \"ccw\" or \"cw\"");
    f.direction = *dir == "cw" ? Direction::kCw : Direction::kCcw;
  }
  if (const auto wrap = r.text("wrap")) {
    if (dim != Dimension::kAngle) r.fail("wrap", "wrap applies to angles; " + what + "is not one");
    if (*wrap == "0..360" || *wrap == "0..2pi") {
      f.wrap = Wrap::kFullTurn;
    } else if (*wrap == "-180..180" || *wrap == "-pi..pi") {
      f.wrap = Wrap::kHalfTurns;
    } else if (*wrap != "none") {
      r.fail("wrap", "wrap must be \"none\", \"0..360\", \"-180..180\", \"0..2pi\" or \"-pi..pi\"");
    }
  }
  if (const auto round = r.boolean("round")) {
    if (!is_integer(f.type)) r.fail("round", "round applies to integer types");
    f.rounding = *round ? Rounding::kNearest : Rounding::kTowardZero;
  }
  // stored = si × stored_per_si + add; a turn in the stored unit.
  f.stored_per_si = units_per(*stored, *given) * (f.direction == native ? 1.0 : -1.0) * f.scale;
  if (f.wrap != Wrap::kNone) {
    f.turn = std::fabs(stored->factor * 2 * std::pow(std::numbers::pi, 1 + stored->pi_power) * f.scale);
  }
}

// How true and false, enum names and agents map to what is stored.
void read_symbols(Reader& r, const QuantityInfo& q, FieldLayout& f) {
  const std::string what = std::string(q.name) + " ";
  const auto [low, high] = range_of(f.type);
  for (const char* key : {"true", "false"}) {
    const auto v = r.number(key);
    if (!v) continue;
    if (q.kind != QuantityKind::kBool) r.fail(key, std::string(key) + " applies to true/false quantities");
    if (f.type == ScalarType::kBool) r.fail(key, std::string(key) + " applies to a non-bool field (a bool is 0 or 1)");
    if (*v < low || *v > high) r.fail(key, std::string(key) + " must fit " + std::string(name_of(f.type)));
    (key[0] == 't' ? f.true_value : f.false_value) = *v;
  }
  if (f.true_value == f.false_value) r.fail("true", "true and false must be stored differently");
  if (const toml::node* values = r.node("values")) {
    if (q.kind != QuantityKind::kEnum) r.fail(values, "values applies to enum quantities; " + what + "is not one");
    const auto* table = values->as_table();
    if (table == nullptr) r.fail(values, "values must be a table, e.g. values = { stop = 1, start = 3 }");
    const std::span<const std::string_view> names = q.names;
    for (const auto& [k, v] : *table) {
      const std::string key(k.str());
      if (std::find(names.begin(), names.end(), key) == names.end()) {
        r.fail(&v, "values: " + key + " is not a value of " + std::string(q.name) + ";" + did_you_mean(key, names) +
                       " they are " + join(names));
      }
      const auto* i = v.as_integer();
      if (i == nullptr) r.fail(&v, "values: " + key + " must be a whole number (the stored integer)");
      if (static_cast<double>(i->get()) < low || static_cast<double>(i->get()) > high) {
        r.fail(&v, "values: " + key + " does not fit " + std::string(name_of(f.type)));
      }
      f.values.push_back({key, i->get()});
    }
    std::sort(f.values.begin(), f.values.end(), [&](const EnumValue& a, const EnumValue& b) {
      return a.value < b.value || (a.value == b.value && a.name < b.name);
    });
  } else if (q.kind == QuantityKind::kEnum) {
    r.fail(nullptr, what + "is an enum: give values = { " + std::string(q.names[0]) + " = <integer>, ... } with " +
                        "the integers the team's agent uses");
  }
  if (const auto index = r.text("index")) {
    if (!q.per_agent) r.fail("index", what + "is not per agent: remove index");
    if (*index != "agent") r.fail("index", "index must be \"agent\" (an array with one element per robot)");
    f.by_agent = true;
  } else if (q.per_agent) {
    r.fail(nullptr, what + "is per agent: give index = \"agent\" and count = the number of robots");
  }
  if (const auto base = r.integer("index_base", 0, 1000)) {
    if (!f.by_agent) r.fail("index_base", "index_base goes with index = \"agent\"");
    f.index_base = static_cast<long>(*base);
  }
}

// One field: where it is (type, offset, count, stride, components) and what it
// holds (from: a quantity, value: a constant, neither: zeros).
FieldLayout read_field(Reader& r, const std::string& item, const std::string& name) {
  FieldLayout f;
  f.name = name;
  f.line = r.line();
  const auto type = r.text("type");
  if (!type) r.fail(nullptr, "missing type; give one of i8, u8, i16, u16, i32, u32, i64, u64, f32, f64, bool");
  const auto t = std::find_if(kTypes.begin(), kTypes.end(), [&](const auto& p) { return p.first == *type; });
  if (t == kTypes.end()) {
    std::vector<std::string_view> names(kTypes.size());
    std::transform(kTypes.begin(), kTypes.end(), names.begin(), [](const auto& p) { return p.first; });
    r.fail("type", "unknown type " + *type + ";" + did_you_mean(*type, names) + " the types are " + join(names));
  }
  f.type = t->second;
  if (!r.has("offset")) r.fail(nullptr, "missing offset; give the field's byte offset in the item (offsetof)");
  f.offset_bytes = static_cast<std::size_t>(*r.integer("offset", 0, kMaxItemBytes));
  f.count = static_cast<std::size_t>(r.integer("count", 1, kMaxItemBytes).value_or(1));
  f.components = static_cast<std::size_t>(r.integer("components", 1, 64).value_or(1));
  f.stride_bytes =
      static_cast<std::size_t>(r.integer("stride", static_cast<std::int64_t>(f.element_bytes()), kMaxItemBytes)
                                   .value_or(static_cast<std::int64_t>(f.element_bytes())));
  const auto from = r.text("from");
  const toml::node* value = r.node("value");
  if (from && value != nullptr) r.fail(value, "a field has from (a quantity) or value (a constant), not both");
  const auto [low, high] = range_of(f.type);
  if (value != nullptr) {
    if (const auto* b = value->as_boolean()) {
      f.value = b->get() ? 1.0 : 0.0;
    } else if (const auto* i = value->as_integer()) {
      f.value = static_cast<double>(i->get());
    } else if (const auto* d = value->as_floating_point(); d != nullptr && !is_integer(f.type)) {
      f.value = d->get();
    }
    if (!f.value || !std::isfinite(*f.value) || *f.value < low || *f.value > high) {
      r.fail(value, "value must be " + std::string(f.type == ScalarType::kBool ? "true or false"
                                                   : is_integer(f.type)
                                                       ? "a whole number that fits " + std::string(name_of(f.type))
                                                       : "a number"));
    }
  }
  if (!from) {
    for (std::string_view k : kConversionKeys) {
      if (r.has(std::string(k))) r.fail(std::string(k), std::string(k) + " has no meaning without from");
    }
    return f;
  }
  const QuantityInfo* q = find_quantity(item, *from);
  if (q == nullptr) unknown_quantity(r, item, *from);
  f.quantity = *from;
  check_shape(r, *q, f);
  read_conversion(r, *q, f);
  read_symbols(r, *q, f);
  return f;
}

constexpr std::array<std::string_view, 3> kItemKeys{"size", "description", "deltas_frame"};

// A table of fields, or of groups of fields (`playerInfo.running = {...}`);
// at the item's level its settings (kItemKeys) are skipped.
void read_fields(const toml::table& table, const std::string& file, const std::string& item, const std::string& prefix,
                 std::vector<FieldLayout>& out) {
  for (const auto& [k, v] : table) {
    const std::string name = prefix + std::string(k.str());
    if (prefix.empty() && std::find(kItemKeys.begin(), kItemKeys.end(), name) != kItemKeys.end()) continue;
    const auto* t = v.as_table();
    if (t == nullptr) {
      throw LayoutError(file, line_of(v), item + "." + name,
                        "unknown key;" + (prefix.empty() ? did_you_mean(name, kItemKeys) : std::string()) +
                            " an item takes size, description, deltas_frame (CMD_POS) and fields (inline tables "
                            "such as vx = { type = \"f32\", offset = 0, from = \"vx\", unit = \"m/s\" })");
    }
    const bool group =
        !t->empty() && std::all_of(t->begin(), t->end(), [](const auto& kv) { return kv.second.is_table(); });
    if (group) {
      read_fields(*t, file, item, name + ".", out);
      continue;
    }
    Reader r(*t, file, item + "." + name, line_of(v));
    r.reject_unknown(kFieldKeys, "fields");
    out.push_back(read_field(r, item, name));
  }
}

void check_bytes(const std::vector<FieldLayout>& fields, std::size_t size, const std::string& file,
                 const std::string& item) {
  struct Span {
    std::size_t begin, end, field;
  };
  std::vector<Span> spans;
  for (std::size_t i = 0; i < fields.size(); ++i) {
    const FieldLayout& f = fields[i];
    if (f.end_bytes() > size) {
      std::ostringstream os;
      os << "the field ends at byte " << f.end_bytes();
      if (f.count > 1)
        os << " (offset " << f.offset_bytes << " + (count - 1) x stride " << f.stride_bytes << " + "
           << f.element_bytes() << ")";
      os << ", past the item's size " << size << "; check offset, count and stride, or the item's size";
      throw LayoutError(file, f.line, item + "." + f.name, os.str());
    }
    if (f.stride_bytes == f.element_bytes()) {  // back to back: one span
      spans.push_back({f.offset_bytes, f.end_bytes(), i});
      continue;
    }
    for (std::size_t e = 0; e < f.count; ++e) {
      const std::size_t b = f.offset_bytes + e * f.stride_bytes;
      spans.push_back({b, b + f.element_bytes(), i});
    }
  }
  std::sort(spans.begin(), spans.end(), [](const Span& a, const Span& b) { return a.begin < b.begin; });
  for (std::size_t k = 1; k < spans.size(); ++k) {
    const Span& a = spans[k - 1];
    const Span& b = spans[k];
    if (b.begin >= a.end) continue;
    const FieldLayout& fa = fields[a.field];
    const FieldLayout& fb = fields[b.field];
    const bool b_later = fb.line > fa.line || (fb.line == fa.line && b.field > a.field);
    const FieldLayout& later = b_later ? fb : fa;
    const FieldLayout& earlier = b_later ? fa : fb;
    const Span& ls = b_later ? b : a;
    const Span& es = b_later ? a : b;
    throw LayoutError(file, later.line, item + "." + later.name,
                      "bytes " + std::to_string(ls.begin) + ".." + std::to_string(ls.end - 1) + " overlap " +
                          earlier.name + " (line " + std::to_string(earlier.line) + ", bytes " +
                          std::to_string(es.begin) + ".." + std::to_string(es.end - 1) +
                          "); two fields cannot share bytes: check the offsets");
  }
}

ItemLayout read_item(const toml::table& table, const std::string& file, const std::string& item, int line) {
  Reader r(table, file, item, line);
  const auto size = r.integer("size", 1, kMaxItemBytes);
  if (!size) r.fail(nullptr, "missing size; give the item's size in bytes (sizeof the C struct)");
  r.text("description");
  DeltasFrame frame = DeltasFrame::kOdometry;
  if (const auto f = r.text("deltas_frame")) {
    if (item != "CMD_POS") r.fail("deltas_frame", "deltas_frame is a setting of CMD_POS only");
    if (*f != "robot" && *f != "odometry") r.fail("deltas_frame", "deltas_frame must be \"robot\" or \"odometry\"");
    frame = *f == "robot" ? DeltasFrame::kRobot : DeltasFrame::kOdometry;
  }
  std::vector<FieldLayout> out;
  read_fields(table, file, item, "", out);
  std::stable_sort(out.begin(), out.end(), [](const FieldLayout& a, const FieldLayout& b) { return a.line < b.line; });
  check_bytes(out, static_cast<std::size_t>(*size), file, item);
  for (const FieldLayout& f : out) {
    const std::string base =
        f.quantity.size() > 6 && f.quantity.ends_with(".count") ? f.quantity.substr(0, f.quantity.size() - 6) : "";
    if (!base.empty() &&
        std::none_of(out.begin(), out.end(), [&](const FieldLayout& g) { return g.quantity == base; })) {
      throw LayoutError(file, f.line, item + "." + f.name,
                        f.quantity + " without a field for " + base + "; add the list or remove the count");
    }
  }
  return LayoutBuilder::make_item(item, static_cast<std::size_t>(*size), file, line, frame, std::move(out));
}

// For a TOML syntax error: the item (last [header] above) and the key on the line.
std::string where_in_text(std::string_view text, int line) {
  static const std::regex kHeader(R"(^\s*\[\s*([^\]\s]+)\s*\])");
  static const std::regex kKey(R"(^\s*("[^"]*"|[A-Za-z0-9_.\-]+)\s*=)");
  std::string item;
  std::string key;
  std::istringstream in{std::string(text)};
  std::string l;
  for (int n = 1; std::getline(in, l) && n <= line; ++n) {
    std::smatch m;
    if (std::regex_search(l, m, kHeader)) {
      item = m[1];
      key.clear();
    }
    if (n == line && std::regex_search(l, m, kKey)) key = m[1];
  }
  if (key.size() >= 2 && key.front() == '"') key = key.substr(1, key.size() - 2);
  if (item.empty() || item == "layout") return key;
  return key.empty() ? item : item + "." + key;
}

}  // namespace

Layout Layout::parse(std::string_view text, const std::string& file_name) {
  toml::table root;
  try {
    root = toml::parse(text, file_name);
  } catch (const toml::parse_error& e) {
    const int line = static_cast<int>(e.source().begin.line);
    throw LayoutError(file_name, line, where_in_text(text, line),
                      "not valid TOML: " + std::string(e.description()) + "; see docs/layouts.md for the format");
  }
  Layout::Data data;
  data.file = file_name;
  data.name = std::filesystem::path(file_name).stem().string();
  std::vector<std::pair<int, ItemLayout>> items;
  for (const auto& [k, v] : root) {
    const std::string key(k.str());
    const auto* t = v.as_table();
    if (key == "layout") {
      if (t == nullptr) throw LayoutError(file_name, line_of(v), key, "layout must be a table: [layout]");
      Reader r(*t, file_name, "layout", line_of(v));
      r.reject_unknown(kLayoutKeys, "[layout] tables");
      if (auto name = r.text("name")) data.name = std::move(*name);
      if (auto description = r.text("description")) data.description = std::move(*description);
      continue;
    }
    if (t == nullptr) {
      throw LayoutError(
          file_name, line_of(v), key,
          "a description holds [layout] and one table per RTDB item ([" + key + "] with size and fields)");
    }
    items.emplace_back(line_of(v), read_item(*t, file_name, key, line_of(v)));
  }
  std::stable_sort(items.begin(), items.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  for (auto& [line, item] : items) data.items.push_back(std::move(item));
  return LayoutBuilder::make_layout(std::move(data));
}

Layout Layout::load(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) {
    throw LayoutError(file.string(), 0, "",
                      "cannot read this layout description (does it exist?); give a file, or a shipped layout: "
                      "cambada, canhil");
  }
  std::ostringstream buf;
  buf << in.rdbuf();
  return parse(buf.str(), file.string());
}

}  // namespace canhil::rtdb
