// loopback_serial.cpp — see loopback_serial.hpp.
#include "hal/loopback/loopback_serial.hpp"

namespace scopekin::hal {

std::size_t LoopbackSerialPort::put(Ring& ring, std::span<const std::uint8_t> bytes) {
    std::size_t written = 0;
    for (const std::uint8_t byte : bytes) {  // bound: bytes.size()
        if (ring.count == kLoopbackSerialCapacity) {
            break;
        }
        ring.bytes[(ring.head + ring.count) % kLoopbackSerialCapacity] = byte;
        ++ring.count;
        ++written;
    }
    return written;
}

std::size_t LoopbackSerialPort::take(Ring& ring, std::span<std::uint8_t> buffer) {
    std::size_t taken = 0;
    while (taken < buffer.size() && ring.count > 0) {  // bound: buffer.size()
        buffer[taken] = ring.bytes[ring.head];
        ring.head = (ring.head + 1U) % kLoopbackSerialCapacity;
        --ring.count;
        ++taken;
    }
    return taken;
}

std::size_t LoopbackSerialPort::device_write(std::span<const std::uint8_t> bytes) {
    const std::size_t written = put(to_box_, bytes);
    counters_.overruns += static_cast<std::uint32_t>(bytes.size() - written);
    return written;
}

std::size_t LoopbackSerialPort::device_read(std::span<std::uint8_t> buffer) {
    return take(from_box_, buffer);
}

SerialTransfer LoopbackSerialPort::read(std::span<std::uint8_t> buffer,
                                        std::uint32_t /*timeout_us*/) {
    const std::size_t count = take(to_box_, buffer);
    counters_.bytes_received += static_cast<std::uint32_t>(count);
    return SerialTransfer{count > 0 ? SerialStatus::ok : SerialStatus::timeout, count};
}

SerialTransfer LoopbackSerialPort::write(std::span<const std::uint8_t> bytes,
                                         std::uint32_t /*timeout_us*/) {
    const std::size_t count = put(from_box_, bytes);
    counters_.bytes_sent += static_cast<std::uint32_t>(count);
    return SerialTransfer{count > 0 || bytes.empty() ? SerialStatus::ok : SerialStatus::timeout,
                          count};
}

}  // namespace scopekin::hal
