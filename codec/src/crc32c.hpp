#pragma once
// CRC-32C (Castagnoli, reflected polynomial 0x82F63B78), as iSCSI and ext4 use it.
#include <cstdint>
#include <span>

namespace reprise::codec {

uint32_t crc32c(std::span<const uint8_t> bytes, uint32_t crc = 0);

}  // namespace reprise::codec
