// The store's image decoders take only the format they store: a damaged blob in another format
// never reaches OpenCV's other decoders (its DICOM reader aborts the process on some inputs,
// found by fuzz_keyframe_codec).

#include "store/keyframe_codec.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace objmap::store_internal {
namespace {

// 128 bytes of preamble and "DICM": what makes a blob a DICOM file to OpenCV.
std::vector<std::uint8_t> DicomLookingBlob() {
  std::vector<std::uint8_t> blob(128, 0x0d);
  for (char c : std::string("DICM")) blob.push_back(static_cast<std::uint8_t>(c));
  blob.push_back(0x01);
  blob.push_back(0xd8);
  return blob;
}

TEST(KeyframeCodec, ABlobOfAnotherFormatIsRefusedBeforeDecoding) {
  const std::vector<std::uint8_t> dicom = DicomLookingBlob();
  std::string why;
  ColorImage color;
  EXPECT_FALSE(DecodeColorJpeg(dicom.data(), dicom.size(), 4, 4, &color, &why));
  EXPECT_EQ(why, "image blob is not a JPEG image");
  std::vector<std::uint16_t> depth;
  EXPECT_FALSE(DecodeDepthPng(dicom.data(), dicom.size(), 4, 4, &depth, &why));
  EXPECT_EQ(why, "image blob is not a PNG image");

  // A JPEG where a PNG belongs is refused too, and the round trips still work.
  ColorImage image;
  image.width = 8;
  image.height = 6;
  image.rgb.assign(8 * 6 * 3, 200);
  Bytes jpeg;
  ASSERT_TRUE(EncodeColorJpeg(image, 90, &jpeg, &why)) << why;
  EXPECT_FALSE(DecodeDepthPng(jpeg.data(), jpeg.size(), 8, 6, &depth, &why));
  EXPECT_EQ(why, "image blob is not a PNG image");
  ASSERT_TRUE(DecodeColorJpeg(jpeg.data(), jpeg.size(), 8, 6, &color, &why)) << why;
  EXPECT_EQ(color.width, 8);
  Bytes png;
  ASSERT_TRUE(EncodeDepthPng(std::vector<std::uint16_t>(48, 1234), 8, 6, &png, &why)) << why;
  ASSERT_TRUE(DecodeDepthPng(png.data(), png.size(), 8, 6, &depth, &why)) << why;
  EXPECT_EQ(depth[0], 1234);
}

}  // namespace
}  // namespace objmap::store_internal
