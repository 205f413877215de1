// laptop/src/rtdb_item.hpp — one RTDB item as the reference handler and
// agent use it: its id in the team's table and a buffer in the team's layout,
// checked once against both (private to laptop/).
#pragma once

#include <initializer_list>
#include <memory>
#include <string_view>

#include "canhil/rtdb/database.hpp"
#include "canhil/rtdb/layout.hpp"

namespace canhil::laptop {

struct Item {
  int id = -1;
  std::unique_ptr<rtdb::ItemBuffer> buf;
  explicit operator bool() const noexcept { return buf != nullptr; }
  rtdb::Quantity q(std::string_view name) const { return buf->quantity(name); }
};

/// Item `name` of agent `space`'s database, carrying every one of
/// `quantities` in `layout`; LayoutError or SetupError naming what is
/// missing, or an empty Item when not `required` and the layout lacks it.
inline Item resolve(rtdb::Database& db, const rtdb::Layout& layout, int space, std::string_view name,
                    std::initializer_list<std::string_view> quantities, bool required) {
  if (!required && layout.item(name) == nullptr) return {};
  const rtdb::ItemLayout& item = rtdb::require(layout, name, quantities);
  Item out;
  out.id = db.require(name, item.size_bytes(), space);
  out.buf = std::make_unique<rtdb::ItemBuffer>(item);
  return out;
}

/// Owner `owner`'s item as agent `space`'s database holds it (a never-written one reads as zeros).
inline void read_item(rtdb::Database& db, int space, int owner, Item& i) {
  if (!db.get(space, owner, i.id, i.buf->bytes())) i.buf->clear();
}
/// Agent `space`'s own item, written fresh (age 0).
inline void write_item(rtdb::Database& db, int space, const Item& i) { db.put(space, space, i.id, i.buf->bytes(), 0); }

}  // namespace canhil::laptop
