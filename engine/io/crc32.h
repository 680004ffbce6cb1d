// CRC-32 (the IEEE 802.3 / zlib polynomial, reflected, 0xEDB88320): the checksum that guards
// training checkpoints against truncation and flipped bits.
#pragma once
#include <cstddef>
#include <cstdint>

namespace evflow::io {

// The CRC-32 of `size` bytes, continuing from `crc` (0 for a fresh sum), so that
// crc32(b, nb, crc32(a, na)) == crc32 of a followed by b. crc32("123456789", 9) == 0xCBF43926.
uint32_t crc32(const void* data, size_t size, uint32_t crc = 0);

}  // namespace evflow::io
