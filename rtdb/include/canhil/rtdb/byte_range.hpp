// canhil/rtdb/byte_range.hpp — a span of an item's bytes, by offset: what an
// ItemBuffer says it changed and what Database::put_ranges copies.
#pragma once

#include <cstddef>

namespace canhil::rtdb {

/// Bytes [offset, offset + size) of an item.
struct ByteRange {
  std::size_t offset = 0;
  std::size_t size = 0;
};

}  // namespace canhil::rtdb
