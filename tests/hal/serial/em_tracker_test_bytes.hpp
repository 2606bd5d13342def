// em_tracker_test_bytes.hpp — hand-built EM-tracker input for the framer and driver tests.
//
// Test support (every preset, bare metal included: fixed capacity, no heap, no exceptions): the
// spec's example messages (test_em_tracker_frame.cpp checks their frames byte for byte) and a
// byte stream that raw bytes and encoded pose / tip force frames are appended to, in order (bytes
// beyond the capacity are dropped).  The framer test feeds the stream to the framer, the driver
// test's scripted port hands it out.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

#include "protocol/em_tracker/em_tracker_frame.hpp"

namespace scopekin::test {

// em_tracker_serial.md §5.
inline constexpr protocol::EmPoseMessage kSpecPose{
    1'000'000U, 0U, 0U, {12'345, -6'789, 250'000}, {11585, 0, 0, 11585}};
inline constexpr protocol::TipForceMessage kSpecTipForce{1'000'250U, 0U, {-150, 40, 2'500}};

/// The spec's pose from another sensor at another device time.
constexpr protocol::EmPoseMessage spec_pose(std::uint8_t sensor, std::uint32_t time_us) noexcept {
    protocol::EmPoseMessage message = kSpecPose;
    message.sensor_id = sensor;
    message.device_time_us = time_us;
    return message;
}

/// The spec's tip force at another device time.
constexpr protocol::TipForceMessage spec_tip_force(std::uint32_t time_us) noexcept {
    protocol::TipForceMessage message = kSpecTipForce;
    message.device_time_us = time_us;
    return message;
}

/// A byte stream of at most `Capacity` bytes, built by appending.
template <std::size_t Capacity>
struct EmTrackerTestBytes {
    std::array<std::uint8_t, Capacity> bytes{};
    std::size_t size{0};

    void add(std::span<const std::uint8_t> more) noexcept {
        for (const std::uint8_t byte : more) {
            if (size < bytes.size()) {
                bytes[size] = byte;
                ++size;
            }
        }
    }
    void add_pose(const protocol::EmPoseMessage& message) noexcept {
        std::array<std::uint8_t, protocol::kEmTrackerMaxFrameSize> frame{};
        add(std::span<const std::uint8_t>{frame.data(), protocol::encode_em_pose(message, frame)});
    }
    void add_tip_force(const protocol::TipForceMessage& message) noexcept {
        std::array<std::uint8_t, protocol::kEmTrackerMaxFrameSize> frame{};
        add(std::span<const std::uint8_t>{frame.data(),
                                          protocol::encode_tip_force(message, frame)});
    }
    [[nodiscard]] std::span<const std::uint8_t> view() const noexcept {
        return std::span<const std::uint8_t>{bytes.data(), size};
    }
};

}  // namespace scopekin::test
