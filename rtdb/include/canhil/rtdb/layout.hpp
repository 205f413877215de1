// canhil/rtdb/layout.hpp — what canhil writes into and reads from a team's
// RTDB, described per item: fields, types, offsets, capacities, units and
// conventions (docs/layouts.md).
//
// canhil thinks in its own quantities, in SI units (a velocity `vx` in m/s,
// line points in metres, voltages in volts, ...; `contract()` lists them). A
// layout says where each quantity sits in a team's C struct and how it is
// stored there: `VISION_INFO.lines` as 500 (x, y) float pairs in millimetres
// at byte 4008, `CMD_INFO.v_logic` as an unsigned short in 0.1 V. canhil ships
// two layouts, `cambada` (the public CAMBADA structs) and `canhil` (its own
// rtdb/include/canhil/rtdb/cambada_types.h); a team with other structs writes
// a description file and canhil's code does not change.
//
//   const Layout layout = Layout::shipped("cambada");          // or Layout::load(path)
//   const ItemLayout& vel = require(layout, "CMD_VEL", {"vx", "vy", "va"});
//   ItemBuffer buf(vel);                                        // set-up: allocates
//   const Quantity vx = buf.quantity("vx");                     // set-up: resolve once
//   DB_get(Whoami(), CMD_VEL, buf.data());                      // each cycle: no allocation
//   const double vx_mps = buf.get(vx);
//
// Errors in a description are LayoutError (a SetupError):
//   `FILE:LINE: ITEM.FIELD: what is wrong; what to do`.
//
// Threads: a Layout is immutable once loaded and may be read from any thread;
// copies share it. An ItemBuffer is thread-compatible (one writer, or readers
// only). Byte order: little-endian, as on x86_64 (checked at compile time).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <initializer_list>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "canhil/base/located_error.hpp"
#include "canhil/rtdb/byte_range.hpp"

namespace canhil::rtdb {

/// A mistake in a layout description, or a layout that lacks what a user of
/// it requires. what(): `FILE:LINE: ITEM.FIELD: what is wrong; what to do`
/// (LINE and ITEM.FIELD when known: field() is "ITEM.FIELD", "ITEM" or "").
class LayoutError : public LocatedError {
 public:
  LayoutError(std::string file, int line, std::string field, const std::string& message)
      : LocatedError(std::move(file), line, std::move(field), message) {}
};

/// The C type of a stored value. Integers and floats little-endian; bool is
/// one byte, 0 or 1.
enum class ScalarType : std::uint8_t { kI8, kU8, kI16, kU16, kI32, kU32, kI64, kU64, kF32, kF64, kBool };
std::size_t size_of(ScalarType type) noexcept;       ///< bytes: 1, 1, 2, 2, 4, 4, 8, 8, 4, 8, 1
std::string_view name_of(ScalarType type) noexcept;  ///< "i8" ... "bool"

/// Which way a stored angle (or angular speed) counts positive.
enum class Direction : std::uint8_t { kCcw, kCw };

/// Where a stored angle is brought after conversion: not at all, into
/// [0, one turn) (`"0..360"` or `"0..2pi"`), or into [-half, +half)
/// (`"-180..180"` or `"-pi..pi"`); the turn in the field's own unit.
enum class Wrap : std::uint8_t { kNone, kFullTurn, kHalfTurns };

/// How an integer field stores a converted value: to nearest (halves away
/// from zero, the default) or toward zero (`round = false`).
enum class Rounding : std::uint8_t { kNearest, kTowardZero };

/// The frame of CMD_POS's `dx`, `dy` (item setting `deltas_frame`):
/// the odometry frame (the change of `x`, `y`) or the robot's frame at the
/// time of the write (x right, y forward).
enum class DeltasFrame : std::uint8_t { kOdometry, kRobot };

/// What kind of value a quantity is.
enum class QuantityKind : std::uint8_t {
  kNumber,  ///< a number in an SI unit (or unit 1)
  kBool,    ///< true / false
  kEnum,    ///< one of a fixed set of names, stored as the layout's integer for it
  kPoints,  ///< a list of (x, y) points, written with set_points
  kCount,   ///< how many points a list holds ("<list>.count")
};

/// One quantity of canhil's contract: what canhil gives or takes, per item.
struct QuantityInfo {
  std::string_view item;  ///< RTDB item, e.g. "CMD_VEL"
  std::string_view name;  ///< e.g. "vx", "lines", "lines.count", "running"
  QuantityKind kind;
  std::string_view si_unit;                 ///< the unit canhil uses: "m/s", "rad", "V", "deg" (CMD_IMU.heading), "1"
  bool per_agent;                           ///< an array indexed by agent number (COACH_INFO)
  bool clockwise;                           ///< an angle canhil gives clockwise (CMD_IMU.heading); else CCW
  std::span<const std::string_view> names;  ///< kEnum: the names canhil uses
  std::string_view meaning;                 ///< one line
};

/// canhil's whole contract, item by item (the order of docs/layouts.md).
std::span<const QuantityInfo> contract() noexcept;
/// The contract's entry for item.quantity, or nullptr.
const QuantityInfo* find_quantity(std::string_view item, std::string_view quantity) noexcept;

/// A symbolic value of an enum field: `values = { stop = 1, start = 3 }`.
struct EnumValue {
  std::string name;
  std::int64_t value = 0;
};

/// One field of an item, as its description gives it (defaults filled in),
/// plus what the conversion derives from it.
struct FieldLayout {
  std::string name;  ///< as written: "vx", "playerInfo.running", "error_count[0][1]"
  int line = 0;      ///< in the description file
  ScalarType type = ScalarType::kU8;
  std::size_t offset_bytes = 0;           ///< of element 0 in the item
  std::size_t count = 1;                  ///< array elements
  std::size_t stride_bytes = 0;           ///< between elements (default: components × size_of(type))
  std::size_t components = 1;             ///< values per element (2 for an (x, y) point)
  std::string quantity;                   ///< `from`; empty for a constant or a field left zero
  std::optional<double> value;            ///< `value`: stored as given in every value of the field by clear()
  std::string unit = "1";                 ///< the stored unit
  double scale = 1;                       ///< stored = SI / unit × scale + add
  double add = 0;                         ///< in the stored unit, after scaling
  Direction direction = Direction::kCcw;  ///< of a stored angle (default: the quantity's own)
  Wrap wrap = Wrap::kNone;
  Rounding rounding = Rounding::kNearest;
  double true_value = 1;          ///< a bool quantity in a non-bool field: stored for true
  double false_value = 0;         ///< ... and for false (reads as false; anything else reads true)
  std::vector<EnumValue> values;  ///< an enum quantity's names and their stored integers
  bool by_agent = false;          ///< `index = "agent"`: element = agent number − index_base
  long index_base = 1;
  // Derived (the conversion, precomputed at load):
  double stored_per_si = 1;  ///< unit factor × direction sign × scale
  double turn = 0;           ///< one turn in the stored unit when wrapping, else 0

  std::size_t element_bytes() const noexcept { return components * size_of(type); }
  std::size_t end_bytes() const noexcept { return offset_bytes + (count - 1) * stride_bytes + element_bytes(); }
};

namespace detail {
/// The fields one quantity is written to (in file order; read from the first).
struct Binding {
  const QuantityInfo* info = nullptr;
  std::vector<std::size_t> fields;  ///< indexes into ItemLayout::fields()
  std::size_t capacity = 0;         ///< see ItemLayout::capacity
  std::size_t count = kNone;        ///< a point list's "<list>.count" binding, if carried
  static constexpr std::size_t kNone = static_cast<std::size_t>(-1);
};
}  // namespace detail

/// A quantity of one item layout, resolved once (ItemLayout::quantity); empty
/// when the layout does not carry it. Valid as long as the Layout.
class Quantity {
 public:
  Quantity() = default;
  explicit operator bool() const noexcept { return binding_ != nullptr; }
  std::string_view name() const noexcept;  ///< "" when empty
  QuantityKind kind() const noexcept;      ///< kNumber when empty

 private:
  friend class ItemLayout;
  friend class ItemBuffer;
  explicit Quantity(const detail::Binding* binding) : binding_(binding) {}
  const detail::Binding* binding_ = nullptr;
};

/// One RTDB item's layout: its size and fields. Not copyable (handles point
/// into it); it lives in its Layout.
class ItemLayout {
 public:
  ItemLayout(const ItemLayout&) = delete;
  ItemLayout& operator=(const ItemLayout&) = delete;
  ItemLayout(ItemLayout&&) noexcept = default;
  ItemLayout& operator=(ItemLayout&&) noexcept = default;
  ~ItemLayout() = default;

  const std::string& name() const noexcept { return name_; }
  std::size_t size_bytes() const noexcept { return size_bytes_; }  ///< sizeof the team's C struct
  const std::string& file() const noexcept { return file_; }       ///< the description it came from
  int line() const noexcept { return line_; }
  std::span<const FieldLayout> fields() const noexcept { return fields_; }  ///< in file order
  const FieldLayout* field(std::string_view c_name) const noexcept;         ///< nullptr when absent
  /// The quantity's handle; empty when this layout does not carry it. A name
  /// outside canhil's contract for this item is a bug in the caller and
  /// aborts (CANHIL_DEMAND); for an item outside the contract every handle is
  /// empty.
  Quantity quantity(std::string_view name) const;
  bool has(std::string_view quantity) const noexcept;
  /// Points a list holds (the smallest count of its fields), elements of a
  /// per-agent array, 1 for another carried quantity, 0 when not carried.
  std::size_t capacity(std::string_view quantity) const noexcept;
  /// CMD_POS's `deltas_frame` (kOdometry when not given, and for other items).
  DeltasFrame deltas_frame() const noexcept { return deltas_frame_; }
  /// The quantities this layout carries, in contract order.
  std::vector<std::string_view> quantities() const;

 private:
  friend struct LayoutBuilder;
  friend class ItemBuffer;
  ItemLayout() = default;
  std::string name_;
  std::size_t size_bytes_ = 0;
  std::string file_;
  int line_ = 0;
  DeltasFrame deltas_frame_ = DeltasFrame::kOdometry;
  std::vector<FieldLayout> fields_;
  std::vector<detail::Binding> bindings_;
};

/// A description: one ItemLayout per item it describes. Immutable; copies
/// share the items (an ItemLayout lives as long as any copy of its Layout).
class Layout {
 public:
  /// Reads and checks a description file. LayoutError on any mistake
  /// (unknown type, unit, key or quantity, a field past the item's size,
  /// overlapping fields, bad TOML, ...). A layout that lacks an item or
  /// quantity canhil needs is not an error here: users call require().
  static Layout load(const std::filesystem::path& file);
  /// The same from text; file_name is only for messages.
  static Layout parse(std::string_view toml, const std::string& file_name);
  /// A layout canhil ships ("cambada", "canhil"); LayoutError naming the choices.
  static Layout shipped(std::string_view name);
  /// Where a shipped layout's file is: CANHIL_LAYOUT_DIR if set, next to the
  /// binary in ../share/canhil/layouts/, else the source tree's rtdb/layouts/.
  /// LayoutError for an unknown name.
  static std::filesystem::path shipped_path(std::string_view name);
  static std::span<const std::string_view> shipped_names() noexcept;  ///< "cambada", "canhil"

  const std::string& name() const noexcept;                      ///< [layout] name
  const std::string& description() const noexcept;               ///< [layout] description
  const std::string& file() const noexcept;                      ///< the file it came from (as given)
  const ItemLayout* item(std::string_view name) const noexcept;  ///< nullptr when not described
  std::vector<std::string> items() const;                        ///< item names in file order

 private:
  struct Data;
  explicit Layout(std::shared_ptr<const Data> data) : data_(std::move(data)) {}
  std::shared_ptr<const Data> data_;
  friend struct LayoutBuilder;
};

/// The item, checked to carry every one of `quantities`; LayoutError naming
/// the layout's file, the item and the first missing quantity (and what to add).
const ItemLayout& require(const Layout& layout, std::string_view item,
                          std::initializer_list<std::string_view> quantities);
/// LayoutError when the RTDB's item (DB_item_size) is not the layout's size.
void check_size(const Layout& layout, const ItemLayout& item, std::size_t rtdb_item_bytes);

/// One item's bytes, sized to its layout, with typed access by quantity.
/// After construction nothing allocates except the error path of the enum
/// set(). Writing a quantity the layout does not carry (an empty handle) does
/// nothing; reading one gives 0. An index past a field's elements is ignored
/// the same way.
class ItemBuffer {
 public:
  /// Zeros, then every `value` constant. The ItemLayout must outlive the buffer.
  explicit ItemBuffer(const ItemLayout& item);

  const ItemLayout& layout() const noexcept { return *item_; }
  /// Zeros, then every `value` constant (the item as canhil writes it fresh).
  void clear() noexcept;
  /// = layout().quantity(name).
  Quantity quantity(std::string_view name) const { return item_->quantity(name); }

  /// Stores `si` (in the quantity's SI unit) in every field that carries q:
  /// v = si × stored_per_si (unit, direction, scale) + add; wrapped; for an
  /// integer rounded (and wrapped again if rounding reached the range's end);
  /// then saturated into the field's type (an integer takes the nearest value
  /// it holds, NaN stores 0; an f32 at most ±FLT_MAX). A bool quantity is
  /// true for anything but 0 and NaN and stores true_value / false_value (1 / 0
  /// in a bool). `index`: the agent number for a per-agent quantity, else 0.
  /// An enum quantity given a number stores that number.
  void set(Quantity q, double si, std::size_t index = 0) noexcept;
  /// Stores an enum quantity's integer for `name`. LayoutError when the
  /// layout gives no integer for it (the message lists the ones it gives).
  void set(Quantity q, std::string_view name, std::size_t index = 0);
  /// Writes min(points.size(), capacity) (x, y) points (SI) into the list
  /// and that number into "<list>.count". Elements past them are left as
  /// they are (clear() first for zeros).
  void set_points(Quantity list, std::span<const std::array<double, 2>> points) noexcept;
  /// set_points, after putting the elements the list held before back as
  /// clear() leaves them (as many as its "<list>.count" says; all of them
  /// when the layout has no count). A buffer written only so since its last
  /// clear() holds the bytes clear() and set_points would give, without
  /// zeroing the whole item each time (VISION_INFO, 30 times a second a robot).
  /// `changed`, when given, is appended the byte ranges this may have
  /// written (the elements kept and put back, and the count): the rest of the
  /// buffer is as it was (Database::put_ranges copies only these).
  void replace_points(Quantity list, std::span<const std::array<double, 2>> points,
                      std::vector<ByteRange>* changed = nullptr) noexcept;

  /// The quantity back in SI from its first field (a bool as 1 / 0, an enum
  /// as its stored integer); 0 when not carried. Wrapping is not undone.
  double get(Quantity q, std::size_t index = 0) const noexcept;
  /// An enum quantity's name; "" when the stored integer has none.
  std::string_view get_enum(Quantity q, std::size_t index = 0) const noexcept;
  /// Point i of a list, SI; {0, 0} past its capacity.
  std::array<double, 2> get_point(Quantity list, std::size_t i) const noexcept;

  std::span<std::byte> bytes() noexcept { return bytes_; }
  std::span<const std::byte> bytes() const noexcept { return bytes_; }
  void* data() noexcept { return bytes_.data(); }  ///< for DB_put / DB_get
  const void* data() const noexcept { return bytes_.data(); }

 private:
  const ItemLayout* item_;
  std::vector<std::byte> bytes_;
};

}  // namespace canhil::rtdb
