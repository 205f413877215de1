// The fault confinement rules, each from its source: ISO 11898-1:2015 clause
// 12.1.4 (Bosch CAN Specification 2.0 part B, section 8, says the same,
// numbered alike), and Linux's thresholds and states (linux/can/error.h;
// can_state_err_to_state in drivers/net/can/dev/dev.c).
#include "canhil/wire/confinement.hpp"

#include <gtest/gtest.h>
#include <linux/can/error.h>

namespace canhil::wire {
namespace {

static_assert(kWarningLimit == CAN_ERROR_WARNING_THRESHOLD);
static_assert(kPassiveLimit == CAN_ERROR_PASSIVE_THRESHOLD);
static_assert(kBusOffLimit == CAN_BUS_OFF_THRESHOLD);

TEST(Confinement, ATransmittersErrorsAddEightUntilPassiveAt128AndBusOffPast255) {
  // Rule 3: TEC + 8 per error flag a transmitter sends.
  Confinement c;
  for (int i = 1; i <= 11; ++i) c.transmit_error(TransmitError::kOther);
  EXPECT_EQ(c.tec(), 88);
  EXPECT_EQ(c.state(), ControllerState::kErrorActive);
  c.transmit_error(TransmitError::kOther);  // 96: Linux's warning level
  EXPECT_EQ(c.state(), ControllerState::kErrorWarning);
  for (int i = 13; i <= 15; ++i) c.transmit_error(TransmitError::kOther);
  EXPECT_EQ(c.tec(), 120);
  EXPECT_EQ(c.state(), ControllerState::kErrorWarning);
  c.transmit_error(TransmitError::kOther);  // 128: error-passive
  EXPECT_EQ(c.state(), ControllerState::kErrorPassive);
  for (int i = 17; i <= 31; ++i) c.transmit_error(TransmitError::kOther);
  EXPECT_EQ(c.tec(), 248);
  EXPECT_FALSE(c.bus_off());
  c.transmit_error(TransmitError::kOther);  // 256: bus-off ("greater than 255")
  EXPECT_TRUE(c.bus_off());
  EXPECT_EQ(c.state(), ControllerState::kBusOff);
}

TEST(Confinement, TheTwoExceptionsOfRuleThree) {
  // (a) an error-passive transmitter's ACK error with no dominant bit in its passive flag: no change.
  Confinement c;
  for (int i = 0; i < 16; ++i) c.transmit_error(TransmitError::kAckNoDominant);
  EXPECT_EQ(c.tec(), 128) << "an error-active transmitter's ACK errors count";
  for (int i = 0; i < 100; ++i) c.transmit_error(TransmitError::kAckNoDominant);
  EXPECT_EQ(c.tec(), 128) << "a lone node climbs to 128 and stays there";
  EXPECT_EQ(c.state(), ControllerState::kErrorPassive);
  // (b) a stuff error in arbitration on a recessive stuff bit read dominant: no change.
  Confinement d;
  d.transmit_error(TransmitError::kStuffInArbitration);
  EXPECT_EQ(d.tec(), 0);
}

TEST(Confinement, AReceiversErrorsAndRecoveryOnSuccess) {
  Confinement c;
  c.receive_error();  // rule 1
  EXPECT_EQ(c.rec(), 1);
  c.receive_error(true);  // rule 2: a dominant bit first after its own flag
  EXPECT_EQ(c.rec(), 9);
  c.received();  // rule 8: - 1 when 1..127
  EXPECT_EQ(c.rec(), 8);
  for (int i = 0; i < 15; ++i) c.receive_error(true);
  EXPECT_EQ(c.rec(), 128);
  EXPECT_EQ(c.state(), ControllerState::kErrorPassive);
  EXPECT_EQ(c.rx_state(), ControllerState::kErrorPassive);
  EXPECT_EQ(c.tx_state(), ControllerState::kErrorActive);
  c.received();  // above 127: set to 119..127
  EXPECT_EQ(c.rec(), kRecAfterPassiveReception);
  EXPECT_GE(c.rec(), 119);
  EXPECT_LE(c.rec(), 127);
  EXPECT_EQ(c.state(), ControllerState::kErrorWarning);
  for (int i = 0; i < 400; ++i) c.receive_error(true);
  EXPECT_FALSE(c.bus_off()) << "receive errors never take a controller bus-off";
}

TEST(Confinement, ASuccessfulTransmissionTakesOneNeverBelowZero) {
  Confinement c;
  c.transmitted();  // rule 7
  EXPECT_EQ(c.tec(), 0);
  c.transmit_error(TransmitError::kOther);
  c.transmitted();
  EXPECT_EQ(c.tec(), 7);
}

TEST(Confinement, BusOffStaysWhateverHappensUntilRecovered) {
  Confinement c;
  c.force_tec(256);
  EXPECT_TRUE(c.bus_off());
  c.transmitted();
  c.received();
  EXPECT_EQ(c.state(), ControllerState::kBusOff);
  c.recovered();  // 128 x 11 recessive bits: error-active, counters 0
  EXPECT_EQ(c.state(), ControllerState::kErrorActive);
  EXPECT_EQ(c.tec(), 0);
  EXPECT_EQ(c.rec(), 0);
}

TEST(Confinement, LinuxStatesByCounterAsCanStateErrToState) {
  Confinement c;
  for (int i = 0; i < 12; ++i) c.receive_error(true);  // REC 96
  EXPECT_EQ(c.rx_state(), ControllerState::kErrorWarning);
  EXPECT_EQ(c.tx_state(), ControllerState::kErrorActive);
  EXPECT_EQ(c.state(), ControllerState::kErrorWarning) << "the worse of the two";
  EXPECT_STREQ(state_name(ControllerState::kBusOff), "bus-off");
}

}  // namespace
}  // namespace canhil::wire
