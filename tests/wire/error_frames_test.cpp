// Error frames as Linux's CAN drivers give them: linux/can/error.h's layout,
// and can_change_state()'s choice of data[1] (drivers/net/can/dev/dev.c).
#include "canhil/wire/error_frames.hpp"

#include <gtest/gtest.h>
#include <linux/can/error.h>

namespace canhil::wire {
namespace {

static_assert(frames::kErrorClassCounters == CAN_ERR_CNT);
static_assert(frames::kControllerRxWarning == CAN_ERR_CRTL_RX_WARNING);
static_assert(frames::kControllerTxWarning == CAN_ERR_CRTL_TX_WARNING);
static_assert(frames::kControllerRxPassive == CAN_ERR_CRTL_RX_PASSIVE);
static_assert(frames::kControllerTxPassive == CAN_ERR_CRTL_TX_PASSIVE);
static_assert(frames::kControllerActive == CAN_ERR_CRTL_ACTIVE);
static_assert(frames::kProtocolErrorBit0 == CAN_ERR_PROT_BIT0);
static_assert(frames::kProtocolErrorBit1 == CAN_ERR_PROT_BIT1);
static_assert(frames::kProtocolErrorStuff == CAN_ERR_PROT_STUFF);
static_assert(frames::kProtocolErrorForm == CAN_ERR_PROT_FORM);
static_assert(frames::kProtocolErrorTx == CAN_ERR_PROT_TX);
static_assert(frames::kProtocolLocationAck == CAN_ERR_PROT_LOC_ACK);
static_assert(frames::kProtocolLocationAckDelimiter == CAN_ERR_PROT_LOC_ACK_DEL);
static_assert(frames::kProtocolLocationData == CAN_ERR_PROT_LOC_DATA);
static_assert(frames::kProtocolLocationId28To21 == CAN_ERR_PROT_LOC_ID28_21);
static_assert(frames::kProtocolLocationIntermission == CAN_ERR_PROT_LOC_INTERM);
static_assert(frames::kErrorClassRestarted == CAN_ERR_RESTARTED);
static_assert(frames::kErrorClassBusOff == CAN_ERR_BUSOFF);
static_assert(frames::kErrorClassNoAck == CAN_ERR_ACK);

Confinement with(int tx_errors, int rx_errors) {
  Confinement c;
  for (int i = 0; i < tx_errors; ++i) c.transmit_error(TransmitError::kOther);
  for (int i = 0; i < rx_errors; ++i) c.receive_error(true);
  return c;
}

TEST(ErrorFrames, AProtocolErrorCarriesItsKindPlaceAndTheCounters) {
  const Confinement c = with(1, 0);
  const frames::CanFrame f = error_frame(frames::kErrorClassProtocol | frames::kErrorClassBusError,
                                         frames::kProtocolErrorBit1 | frames::kProtocolErrorTx,
                                         frames::kProtocolLocationData, c, ControllerState::kErrorActive);
  EXPECT_EQ(f.kind, frames::FrameKind::kError);
  EXPECT_EQ(f.len, CAN_ERR_DLC);
  EXPECT_EQ(f.id, static_cast<std::uint32_t>(CAN_ERR_PROT | CAN_ERR_BUSERROR | CAN_ERR_CNT));
  EXPECT_EQ(f.data[1], 0) << "no change of state";
  EXPECT_EQ(f.data[2], CAN_ERR_PROT_BIT1 | CAN_ERR_PROT_TX);
  EXPECT_EQ(f.data[3], CAN_ERR_PROT_LOC_DATA);
  EXPECT_EQ(f.data[6], 8);
  EXPECT_EQ(f.data[7], 0);
}

TEST(ErrorFrames, ChangesOfStateAsCanChangeStateReportsThem) {
  // The transmit side worse: its bits only.
  frames::CanFrame f = error_frame(0, 0, 0, with(12, 0), ControllerState::kErrorActive);
  EXPECT_EQ(f.id & CAN_ERR_CRTL, static_cast<std::uint32_t>(CAN_ERR_CRTL));
  EXPECT_EQ(f.data[1], CAN_ERR_CRTL_TX_WARNING);
  // The receive side worse: its bits only.
  f = error_frame(0, 0, 0, with(0, 16), ControllerState::kErrorActive);
  EXPECT_EQ(f.data[1], CAN_ERR_CRTL_RX_PASSIVE);
  // Both alike: both.
  f = error_frame(0, 0, 0, with(16, 16), ControllerState::kErrorWarning);
  EXPECT_EQ(f.data[1], CAN_ERR_CRTL_TX_PASSIVE | CAN_ERR_CRTL_RX_PASSIVE);
  // Back to error-active.
  f = error_frame(0, 0, 0, with(0, 0), ControllerState::kErrorWarning);
  EXPECT_EQ(f.data[1], CAN_ERR_CRTL_ACTIVE);
  // Bus-off: its own class, no controller bits.
  f = error_frame(0, 0, 0, with(32, 0), ControllerState::kErrorPassive);
  EXPECT_EQ(f.id & (CAN_ERR_BUSOFF | CAN_ERR_CRTL), static_cast<std::uint32_t>(CAN_ERR_BUSOFF));
  EXPECT_EQ(f.data[6], 255) << "the counter, as a byte";
}

}  // namespace
}  // namespace canhil::wire
