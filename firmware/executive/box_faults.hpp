// box_faults.hpp — the box's driver-level fault bits (BoxStatus.DriverFaults in scopekin.dbc)
// and the counters behind them (BoxCounters).  A bit is set for every period in which the
// problem was seen (stale and bus-off: for as long as they last).
#pragma once

#include <cstdint>

namespace scopekin::executive {

enum DriverFault : std::uint16_t {
    kFaultForceTorqueStale = 1U << 0U,
    kFaultEncoderStale = 1U << 1U,
    kFaultBadLength = 1U << 2U,
    kFaultUnknownId = 1U << 3U,
    kFaultOutOfRange = 1U << 4U,
    kFaultSensorStatus = 1U << 5U,
    kFaultCounterGap = 1U << 6U,
    kFaultCanErrorFrame = 1U << 7U,
    kFaultBusOff = 1U << 8U,
    kFaultReceiveDropped = 1U << 9U,
    kFaultSendFailed = 1U << 10U,
    kFaultSerialFraming = 1U << 11U,
    kFaultTrackerStale = 1U << 12U,
    kFaultPeriodOverrun = 1U << 13U,
};

}  // namespace scopekin::executive
