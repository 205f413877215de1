// The bus model's fixed bit counts (ISO 11898-1:2015 clause 10.4; Bosch CAN
// 2.0 part B section 3.1.3-3.2), shared by its source files.
#pragma once

#include <cstdint>

#include "canhil/frames/wire.hpp"

namespace canhil::wire::bit_counts {

inline constexpr std::uint32_t kIntermission = frames::kIntermissionBits;
inline constexpr std::uint32_t kErrorFlag = 6;  // an active or passive error flag
inline constexpr std::uint32_t kErrorDelimiter = 8;
inline constexpr std::uint32_t kSuspend = 8;         // an error-passive transmitter's suspend transmission
inline constexpr std::uint32_t kTailRecessive = 11;  // ACK delimiter, end of frame, intermission
inline constexpr std::uint32_t kBusIdle = 11;        // recessive bits a controller waits for to join the bus
// After a frame's last CRC bit: CRC delimiter, ACK slot, ACK delimiter, end of frame, intermission.
inline constexpr std::uint32_t kAfterCrc = 13;
inline constexpr std::uint32_t kAckSlotFromEnd = 12;  // the ACK slot is the 12th bit from a frame's end
// A stuck-dominant bus: the first 8-bit sequence counted at the 14th dominant
// bit after the error flag (rule 6), then every 8.
inline constexpr std::uint32_t kFirstDominantSequence = kErrorFlag + 14;
inline constexpr std::uint32_t kDominantSequence = 8;
// The receive counter stops where an 8-bit register would.
inline constexpr std::uint16_t kRecCeiling = 255;

}  // namespace canhil::wire::bit_counts
