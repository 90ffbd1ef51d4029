#include "types/image_header.h"

#include <cstdint>
#include <string_view>

namespace objmap {
namespace {

std::uint32_t ReadBigEndian(std::string_view data, std::size_t offset, int size) {
  std::uint32_t value = 0;
  for (int i = 0; i < size; ++i) {
    value = (value << 8) | static_cast<unsigned char>(data[offset + i]);
  }
  return value;
}

unsigned char Byte(std::string_view data, std::size_t offset) {
  return static_cast<unsigned char>(data[offset]);
}

// Start-of-frame markers carry the image size: C0..CF except DHT (C4), JPG (C8) and DAC (CC).
bool IsStartOfFrame(unsigned char marker) {
  return marker >= 0xC0 && marker <= 0xCF && marker != 0xC4 && marker != 0xC8 && marker != 0xCC;
}

// Markers without a length field: TEM, RST0..7, SOI, EOI.
bool IsStandalone(unsigned char marker) {
  return marker == 0x01 || (marker >= 0xD0 && marker <= 0xD9);
}

bool ToInt(std::uint32_t width, std::uint32_t height, int* width_out, int* height_out) {
  // PNG allows up to 2^31 - 1; anything that large is refused later anyway.
  if (width == 0 || height == 0 || width > 0x7fffffffu || height > 0x7fffffffu) return false;
  *width_out = static_cast<int>(width);
  *height_out = static_cast<int>(height);
  return true;
}

}  // namespace

bool ReadPngSize(std::string_view data, int* width, int* height) {
  static const char kSignature[] = "\x89PNG\r\n\x1a\n";
  // Signature (8), IHDR length (4), "IHDR" (4), width (4), height (4).
  if (data.size() < 24 || data.compare(0, 8, kSignature, 8) != 0 ||
      data.compare(12, 4, "IHDR") != 0) {
    return false;
  }
  return ToInt(ReadBigEndian(data, 16, 4), ReadBigEndian(data, 20, 4), width, height);
}

bool ReadJpegSize(std::string_view data, int* width, int* height) {
  if (data.size() < 4 || Byte(data, 0) != 0xFF || Byte(data, 1) != 0xD8) return false;
  std::size_t pos = 2;
  while (pos + 1 < data.size()) {
    if (Byte(data, pos) != 0xFF) return false;
    const unsigned char marker = Byte(data, pos + 1);
    if (marker == 0xFF) {  // fill byte before a marker
      ++pos;
      continue;
    }
    if (IsStandalone(marker)) {
      pos += 2;
      continue;
    }
    if (marker == 0xDA || pos + 4 > data.size()) return false;  // scan data before any frame
    const std::uint32_t length = ReadBigEndian(data, pos + 2, 2);
    if (IsStartOfFrame(marker)) {
      // Length (2), precision (1), height (2), width (2).
      if (length < 7 || pos + 9 > data.size()) return false;
      return ToInt(ReadBigEndian(data, pos + 7, 2), ReadBigEndian(data, pos + 5, 2), width, height);
    }
    if (length < 2) return false;
    pos += 2 + length;
  }
  return false;
}

}  // namespace objmap
