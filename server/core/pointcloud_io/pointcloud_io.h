#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "types/organized_cloud.h"

namespace objmap {

/// Reads an organized PCD (fields x y z and rgb or rgba; optional `label`), any PCD encoding.
/// `labels` may be null; when given it receives the label field (empty if the file has none).
[[nodiscard]] bool LoadOrganizedPcd(const std::string& path, OrganizedCloud* cloud,
                                    std::vector<std::uint32_t>* labels, std::string* why);

/// Writes an organized binary PCD with fields x y z rgb label. Segment label s is written as s + 1
/// so that 0 means invalid (-1 in SegmentationResult), as in the mOSD label scheme.
[[nodiscard]] bool SaveLabelledPcd(const std::string& path, const OrganizedCloud& cloud,
                                   const std::vector<std::int32_t>& labels, std::string* why);

/// Reads a PLY that WritePly wrote (binary little-endian, x y z float, red green blue uchar);
/// false with a reason naming the file for anything else.
[[nodiscard]] bool ReadPly(const std::string& path, std::vector<Eigen::Vector3f>* points,
                           std::vector<std::array<std::uint8_t, 3>>* colors, std::string* why);

/// Writes a coloured point set as binary little-endian PLY.
[[nodiscard]] bool WritePly(const std::string& path, const std::vector<Eigen::Vector3f>& points,
                            const std::vector<std::array<std::uint8_t, 3>>& colors,
                            std::string* why);

}  // namespace objmap
