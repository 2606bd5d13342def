// em_tracker_driver.cpp — frames -> validated, time-stamped EM tracker and tip force samples.
// Behaviour per fault: firmware/protocol/em_tracker/em_tracker_serial.md §4; conversions and
// their scaling: em_tracker_driver.hpp.
#include "drivers/em_tracker_driver.hpp"

namespace scopekin::drivers {
namespace {

constexpr std::size_t kTipForceSource = kEmSensorCount;  // index 4

[[nodiscard]] constexpr std::uint8_t source_bit(std::size_t source) noexcept {
    return static_cast<std::uint8_t>(1U << source);
}

/// |value| as int64 (defined for INT32_MIN).
[[nodiscard]] constexpr std::int64_t magnitude(std::int32_t value) noexcept {
    const std::int64_t wide = value;
    return wide < 0 ? -wide : wide;
}

/// Q2.14 -> Q16.16: raw * 2^2, exact (|raw| <= 2^15, product <= 2^17).
[[nodiscard]] constexpr Q16_16 from_q2_14(std::int16_t raw) noexcept {
    return Q16_16::from_raw(static_cast<std::int32_t>(raw) * 4);
}

/// w² + x² + y² + z² of a Q2.14 quaternion is 2^28 (at 2^-28 resolution) for a unit one.
[[nodiscard]] constexpr bool is_unit_quaternion(const std::array<std::int16_t, 4>& q,
                                                Q16_16 tolerance) noexcept {
    std::int64_t sum = 0;
    for (const std::int16_t component : q) {  // bound: 4; each square <= 2^30, sum <= 2^32
        sum += std::int64_t{component} * component;
    }
    constexpr std::int64_t one_q28 = std::int64_t{1} << 28;
    const std::int64_t deviation = sum >= one_q28 ? sum - one_q28 : one_q28 - sum;
    // Q16.16 -> Q28: * 2^12, exact in int64 (|raw| < 2^31).  A negative tolerance accepts only
    // an exact unit norm.
    const std::int64_t allowed = tolerance.raw() > 0 ? std::int64_t{tolerance.raw()} * 4096 : 0;
    return deviation <= allowed;
}

static_assert(is_unit_quaternion({16384, 0, 0, 0}, Q16_16{}));
static_assert(is_unit_quaternion({11585, 0, 0, 11585}, Q16_16::from_ratio(2, 100)));
static_assert(!is_unit_quaternion({0, 0, 0, 0}, Q16_16::from_ratio(2, 100)));

}  // namespace

EmTrackerDriver::EmTrackerDriver(const EmTrackerDriverConfig& config) noexcept
    : config_(config),
      // Missing data is a fault: every monitored source is stale until its first valid sample.
      stale_mask_(static_cast<std::uint8_t>(config.monitored_sources & kEmAllSources)) {}

EmTrackerServiceResult EmTrackerDriver::service(SerialPort& port, std::uint64_t now_us) noexcept {
    EmTrackerServiceResult result;
    std::array<std::uint8_t, kReadChunkBytes> chunk{};
    for (std::size_t read = 0; read < kReadsPerService; ++read) {  // bound: kReadsPerService
        const hal::SerialTransfer transfer = port.read(chunk, 0);
        if (transfer.status == SerialStatus::ok) {
            // A backend that claims more than it was given is clamped, never trusted.
            const std::size_t count = transfer.count < chunk.size() ? transfer.count : chunk.size();
            result.status = SerialStatus::ok;
            result.bytes_read += static_cast<std::uint32_t>(count);
            result.samples += static_cast<std::uint32_t>(
                receive(std::span<const std::uint8_t>{chunk.data(), count}, now_us));
            if (count < chunk.size()) {
                break;  // the port had no more for now
            }
            continue;
        }
        if (transfer.status == SerialStatus::closed) {
            ++counters_.serial_closed;
            event_flags_ |= kEmFaultSerial;
        } else if (transfer.status == SerialStatus::failed) {
            ++counters_.serial_errors;
            event_flags_ |= kEmFaultSerial;
        }
        if (result.status != SerialStatus::ok) {
            result.status = transfer.status;
        }
        break;
    }
    poll(now_us);
    return result;
}

EmTrackerServiceResult EmTrackerDriver::service(SerialPort& port,
                                                const MonotonicClock& clock) noexcept {
    return service(port, clock.now_us());
}

std::size_t EmTrackerDriver::receive(std::span<const std::uint8_t> bytes,
                                     std::uint64_t now_us) noexcept {
    const protocol::EmTrackerFramerCounters before = framer_.counters();
    std::size_t samples = 0;
    std::size_t offset = 0;
    // Each pass pushes at least one byte: after popping every frame fewer than
    // kEmTrackerMaxFrameSize bytes stay buffered, so the ring always has room.  A pass offers no
    // more than that room: a span larger than the ring loses no byte, so it is no overflow
    // (the framer counts one for every push it cannot take whole).  bound: bytes.size()
    while (offset < bytes.size()) {
        const std::size_t room = protocol::kEmTrackerFramerCapacity - framer_.buffered();
        const std::size_t rest = bytes.size() - offset;
        const std::size_t taken = framer_.push(bytes.subspan(offset, rest < room ? rest : room));
        offset += taken;
        protocol::EmTrackerFrame frame;
        // bound: a pop() consumes >= 17 bytes, so at most kEmTrackerFramerCapacity / 17 frames
        for (std::size_t i = 0; i < protocol::kEmTrackerFramerCapacity; ++i) {
            if (!framer_.pop(frame)) {
                break;
            }
            samples += handle_frame(frame, now_us) ? 1U : 0U;
        }
        if (taken == 0U) {
            break;  // cannot happen (see above); never loop without progress
        }
    }
    note_link_faults(before);
    return samples;
}

void EmTrackerDriver::note_link_faults(const protocol::EmTrackerFramerCounters& before) noexcept {
    const protocol::EmTrackerFramerCounters& after = framer_.counters();
    if (after.bad_checksum != before.bad_checksum) {
        event_flags_ |= kEmFaultBadChecksum;
    }
    if (after.bad_length != before.bad_length) {
        event_flags_ |= kEmFaultBadLength;
    }
    if (after.unknown_type != before.unknown_type) {
        event_flags_ |= kEmFaultUnknownType;
    }
    if (after.buffer_overflows != before.buffer_overflows) {
        event_flags_ |= kEmFaultBufferOverflow;
    }
    if (after.bytes_discarded != before.bytes_discarded) {
        event_flags_ |= kEmFaultNoSync;
    }
}

bool EmTrackerDriver::handle_frame(const protocol::EmTrackerFrame& frame,
                                   std::uint64_t now_us) noexcept {
    if (frame.type == protocol::EmTrackerMessageType::pose) {
        protocol::EmPoseMessage message;
        if (protocol::decode_em_pose(frame, message)) {
            handle_pose(message, now_us);
            return true;
        }
    } else if (frame.type == protocol::EmTrackerMessageType::tip_force) {
        protocol::TipForceMessage message;
        if (protocol::decode_tip_force(frame, message)) {
            handle_tip_force(message, now_us);
            return true;
        }
    }
    ++counters_.malformed_payload;  // the framer checked type and length: unreachable
    return false;
}

bool EmTrackerDriver::device_time_increases(std::size_t source,
                                            std::uint32_t device_time_us) noexcept {
    const std::uint8_t bit = source_bit(source);
    bool increases = true;
    if ((device_time_mask_ & bit) != 0U) {
        // Modulo 2^32 (the device clock wraps every 71.6 min): a step of 1 .. 2^31 - 1 µs is
        // forward; 0 (repeated) or >= 2^31 (backwards) is not.
        const std::uint32_t step = device_time_us - last_device_time_us_[source];
        increases = step != 0U && step < (std::uint32_t{1} << 31U);
    }
    // Any well-formed sample becomes the reference, so a tracker restart (time back to ~0)
    // costs one flagged sample, not the 71 minutes until its clock passes the old value.
    last_device_time_us_[source] = device_time_us;
    device_time_mask_ = static_cast<std::uint8_t>(device_time_mask_ | bit);
    return increases;
}

void EmTrackerDriver::count_sample_faults(std::uint32_t flags) noexcept {
    if ((flags & kEmFaultUnknownSensor) != 0U) {
        ++counters_.unknown_sensor;
    }
    if ((flags & kEmFaultOutOfRange) != 0U) {
        ++counters_.out_of_range;
    }
    if ((flags & kEmFaultQuaternionNorm) != 0U) {
        ++counters_.quaternion_norm;
    }
    if ((flags & kEmFaultTimestamp) != 0U) {
        ++counters_.timestamp_backwards;
    }
    if ((flags & kEmFaultDeviceStatus) != 0U) {
        ++counters_.device_status;
    }
    event_flags_ |= flags;
}

void EmTrackerDriver::mark_valid(std::size_t source, std::uint64_t now_us) noexcept {
    const std::uint8_t bit = source_bit(source);
    last_valid_us_[source] = now_us;
    valid_mask_ = static_cast<std::uint8_t>(valid_mask_ | bit);
    stale_mask_ = static_cast<std::uint8_t>(stale_mask_ & ~bit);
}

void EmTrackerDriver::handle_pose(const protocol::EmPoseMessage& message,
                                  std::uint64_t now_us) noexcept {
    EmTrackerSample entry;
    entry.kind = EmTrackerSampleKind::pose;
    EmPoseSample& sample = entry.pose;
    sample.sensor_id = message.sensor_id;
    sample.device_time_us = message.device_time_us;
    sample.receive_time_us = now_us;
    sample.device_status = message.status;

    std::uint32_t flags = 0;
    const std::int64_t max_position = magnitude(config_.max_position_um);
    for (std::size_t axis = 0; axis < 3U; ++axis) {  // bound: 3
        const std::int32_t um = message.position_um[axis];
        // round(um * 2^16 / 1000), saturating beyond ±32767 mm (see the header).
        sample.position_mm[axis] = Q16_16::from_ratio(um, 1000);
        if (magnitude(um) > max_position) {
            flags |= kEmFaultOutOfRange;
        }
    }
    for (std::size_t i = 0; i < 4U; ++i) {  // bound: 4
        sample.orientation[i] = from_q2_14(message.orientation_q14[i]);
    }
    if (!is_unit_quaternion(message.orientation_q14, config_.quaternion_norm_squared_tolerance)) {
        flags |= kEmFaultQuaternionNorm;
    }
    if (message.status != 0U) {
        flags |= kEmFaultDeviceStatus;
    }
    const bool known_sensor = message.sensor_id < kEmSensorCount;
    if (!known_sensor) {
        flags |= kEmFaultUnknownSensor;
    } else if (!device_time_increases(message.sensor_id, message.device_time_us)) {
        flags |= kEmFaultTimestamp;
    }
    sample.fault_flags = flags;
    count_sample_faults(flags);
    if (flags == 0U) {
        ++counters_.poses_ok;
        latest_pose_[message.sensor_id] = sample;
        mark_valid(message.sensor_id, now_us);
    }
    enqueue(entry);
}

void EmTrackerDriver::handle_tip_force(const protocol::TipForceMessage& message,
                                       std::uint64_t now_us) noexcept {
    EmTrackerSample entry;
    entry.kind = EmTrackerSampleKind::tip_force;
    TipForceSample& sample = entry.tip_force;
    sample.device_time_us = message.device_time_us;
    sample.receive_time_us = now_us;
    sample.device_status = message.status;

    std::uint32_t flags = 0;
    const std::int64_t max_force = magnitude(config_.max_force_mN);
    for (std::size_t axis = 0; axis < 3U; ++axis) {  // bound: 3
        const std::int16_t mN = message.force_mN[axis];
        // round(mN * 2^16 / 1000), |mN| <= 32768 -> |N| <= 32.768: never saturates.
        sample.force_N[axis] = Q16_16::from_ratio(mN, 1000);
        if (magnitude(mN) > max_force) {
            flags |= kEmFaultOutOfRange;
        }
    }
    if (message.status != 0U) {
        flags |= kEmFaultDeviceStatus;
    }
    if (!device_time_increases(kTipForceSource, message.device_time_us)) {
        flags |= kEmFaultTimestamp;
    }
    sample.fault_flags = flags;
    count_sample_faults(flags);
    if (flags == 0U) {
        ++counters_.tip_forces_ok;
        latest_force_ = sample;
        mark_valid(kTipForceSource, now_us);
    }
    enqueue(entry);
}

void EmTrackerDriver::enqueue(const EmTrackerSample& sample) noexcept {
    if (queue_size_ == kSampleQueueCapacity) {
        // Keep the newest: drop the oldest.
        queue_head_ = (queue_head_ + 1U) % kSampleQueueCapacity;
        --queue_size_;
        ++counters_.samples_dropped;
        event_flags_ |= kEmFaultQueueOverflow;
    }
    queue_[(queue_head_ + queue_size_) % kSampleQueueCapacity] = sample;
    ++queue_size_;
}

bool EmTrackerDriver::pop(EmTrackerSample& sample) noexcept {
    if (queue_size_ == 0U) {
        return false;
    }
    sample = queue_[queue_head_];
    queue_head_ = (queue_head_ + 1U) % kSampleQueueCapacity;
    --queue_size_;
    return true;
}

void EmTrackerDriver::poll(std::uint64_t now_us) noexcept {
    for (std::size_t source = 0; source < kEmSourceCount; ++source) {  // bound: 5
        const std::uint8_t bit = source_bit(source);
        if ((config_.monitored_sources & bit) == 0U || (valid_mask_ & bit) == 0U ||
            (stale_mask_ & bit) != 0U) {
            continue;  // not monitored, never valid (stale since start), or already stale
        }
        // A caller clock behind the last reception counts as no time elapsed.
        const std::uint64_t last = last_valid_us_[source];
        const std::uint64_t age_us = now_us > last ? now_us - last : 0U;
        if (age_us > config_.stale_timeout_us) {
            stale_mask_ = static_cast<std::uint8_t>(stale_mask_ | bit);
            ++counters_.stale_events;
        }
    }
}

bool EmTrackerDriver::stale(EmSensor sensor) const noexcept {
    const auto index = static_cast<std::size_t>(sensor);
    return index < kEmSensorCount && (stale_mask_ & source_bit(index)) != 0U;
}

bool EmTrackerDriver::tip_force_stale() const noexcept {
    return (stale_mask_ & kEmSourceTipForce) != 0U;
}

const EmPoseSample& EmTrackerDriver::latest_pose(EmSensor sensor) const noexcept {
    const auto index = static_cast<std::size_t>(sensor);
    return latest_pose_[index < kEmSensorCount ? index : 0U];
}

bool EmTrackerDriver::has_pose(EmSensor sensor) const noexcept {
    const auto index = static_cast<std::size_t>(sensor);
    return index < kEmSensorCount && (valid_mask_ & source_bit(index)) != 0U;
}

std::uint32_t EmTrackerDriver::fault_flags() const noexcept {
    return event_flags_ | (stale_mask_ != 0U ? std::uint32_t{kEmFaultStale} : 0U);
}

std::uint32_t EmTrackerDriver::take_fault_flags() noexcept {
    const std::uint32_t flags = fault_flags();
    event_flags_ = 0;
    return flags;
}

EmTrackerDriverCounters EmTrackerDriver::counters() const noexcept {
    EmTrackerDriverCounters result = counters_;
    result.link = framer_.counters();
    return result;
}

}  // namespace scopekin::drivers
