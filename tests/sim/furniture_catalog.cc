#include "sim/furniture_catalog.h"

#include <unzip.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <map>
#include <memory>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <sstream>

namespace objmap::sim {
namespace {

namespace fs = std::filesystem;

// One .sh3f archive, open for reading whole entries.
class ZipArchive {
 public:
  explicit ZipArchive(const std::string& path) : file_(unzOpen64(path.c_str())) {}
  ~ZipArchive() {
    if (file_ != nullptr) unzClose(file_);
  }
  ZipArchive(const ZipArchive&) = delete;
  ZipArchive& operator=(const ZipArchive&) = delete;
  [[nodiscard]] bool ok() const { return file_ != nullptr; }

  // The bytes of `name` (no leading slash); false when absent or unreadable.
  bool Read(const std::string& name, std::string* bytes) {
    if (file_ == nullptr || unzLocateFile(file_, name.c_str(), 1) != UNZ_OK) return false;
    unz_file_info64 info;
    if (unzGetCurrentFileInfo64(file_, &info, nullptr, 0, nullptr, 0, nullptr, 0) != UNZ_OK ||
        unzOpenCurrentFile(file_) != UNZ_OK) {
      return false;
    }
    bytes->resize(info.uncompressed_size);
    const int read = bytes->empty() ? 0
                                    : unzReadCurrentFile(file_, bytes->data(),
                                                         static_cast<unsigned>(bytes->size()));
    unzCloseCurrentFile(file_);
    return read == static_cast<int>(bytes->size());
  }

 private:
  unzFile file_;
};

std::string Trim(std::string s) {
  while (!s.empty() && (s.back() == '\r' || s.back() == ' ' || s.back() == '\t')) s.pop_back();
  std::size_t start = 0;
  while (start < s.size() && (s[start] == ' ' || s[start] == '\t')) ++start;
  return s.substr(start);
}

// Java properties: key=value lines; backslash escapes of single characters are undone.
std::map<std::string, std::string> ParseProperties(const std::string& text) {
  std::map<std::string, std::string> properties;
  std::istringstream lines(text);
  std::string line;
  while (std::getline(lines, line)) {
    line = Trim(line);
    if (line.empty() || line[0] == '#' || line[0] == '!') continue;
    const std::size_t equals = line.find('=');
    if (equals == std::string::npos) continue;
    std::string value;
    const std::string raw = Trim(line.substr(equals + 1));
    for (std::size_t i = 0; i < raw.size(); ++i) {
      if (raw[i] == '\\' && i + 1 < raw.size()) ++i;
      value += raw[i];
    }
    properties[Trim(line.substr(0, equals))] = value;
  }
  return properties;
}

struct Material {
  Eigen::Vector3f diffuse = Eigen::Vector3f::Constant(0.8f);
  std::shared_ptr<const Texture> texture;  // null: the diffuse colour
};

std::shared_ptr<const Texture> DecodeTexture(const std::string& bytes) {
  const cv::Mat bgr = cv::imdecode(
      cv::Mat(1, static_cast<int>(bytes.size()), CV_8UC1, const_cast<char*>(bytes.data())),
      cv::IMREAD_COLOR);
  if (bgr.empty()) return nullptr;
  auto texture = std::make_shared<Texture>();
  texture->width = bgr.cols;
  texture->height = bgr.rows;
  texture->texels.reserve(static_cast<std::size_t>(bgr.cols) * bgr.rows);
  for (int y = 0; y < bgr.rows; ++y) {
    for (int x = 0; x < bgr.cols; ++x) {
      const cv::Vec3b& c = bgr.at<cv::Vec3b>(y, x);
      texture->texels.push_back({c[2], c[1], c[0]});
    }
  }
  return texture;
}

std::map<std::string, Material> ParseMaterials(const std::string& text, const std::string& folder,
                                               ZipArchive* zip) {
  std::map<std::string, Material> materials;
  std::istringstream lines(text);
  std::string line;
  Material* current = nullptr;
  while (std::getline(lines, line)) {
    std::istringstream words(Trim(line));
    std::string keyword;
    words >> keyword;
    if (keyword == "newmtl") {
      std::string name;
      words >> name;
      current = &materials[name];
    } else if (current != nullptr && keyword == "Kd") {
      words >> current->diffuse.x() >> current->diffuse.y() >> current->diffuse.z();
    } else if (current != nullptr && keyword == "map_Kd") {
      std::string file;
      std::getline(words, file);
      file = Trim(file);
      std::string bytes;
      if (zip->Read(folder + file, &bytes)) current->texture = DecodeTexture(bytes);
    }
  }
  return materials;
}

Rgb ColorOf(const Material& material, const Eigen::Vector2f& uv) {
  if (material.texture) return material.texture->Sample(uv);
  const Eigen::Vector3f rgb = material.diffuse;
  Rgb out;
  for (int c = 0; c < 3; ++c)
    out[c] = static_cast<std::uint8_t>(std::clamp(rgb[c] * 255.f, 0.f, 255.f));
  return out;
}

// An OBJ index (1-based, or negative from the end) into a list of `count`.
int Index(const std::string& token, std::size_t count) {
  if (token.empty()) return -1;
  const int i = std::atoi(token.c_str());
  const int index = i > 0 ? i - 1 : static_cast<int>(count) + i;
  return index >= 0 && index < static_cast<int>(count) ? index : -1;
}

}  // namespace

std::unique_ptr<FurnitureCatalog> FurnitureCatalog::Open(const std::string& folder,
                                                         std::string* why) {
  auto catalog = std::unique_ptr<FurnitureCatalog>(new FurnitureCatalog());
  std::error_code error;
  std::vector<fs::path> archives;
  for (const auto& item : fs::directory_iterator(folder, error)) {
    if (item.path().extension() == ".sh3f") archives.push_back(item.path());
  }
  std::sort(archives.begin(), archives.end());
  for (const fs::path& path : archives) {
    ZipArchive zip(path.string());
    std::string text;
    if (!zip.Read("PluginFurnitureCatalog.properties", &text)) continue;
    const std::map<std::string, std::string> properties = ParseProperties(text);
    for (int n = 1;; ++n) {
      const std::string suffix = "#" + std::to_string(n);
      const auto name = properties.find("name" + suffix);
      if (name == properties.end()) break;
      FurnitureEntry entry;
      entry.archive = path.string();
      entry.name = name->second;
      auto get = [&](const char* key) {
        const auto it = properties.find(key + suffix);
        return it == properties.end() ? std::string() : it->second;
      };
      entry.category = get("category");
      entry.model = get("model");
      entry.creator = get("creator");
      entry.size_m = Eigen::Vector3f(std::strtof(get("width").c_str(), nullptr),
                                     std::strtof(get("depth").c_str(), nullptr),
                                     std::strtof(get("height").c_str(), nullptr)) /
                     100.f;
      std::istringstream rotation(get("modelRotation"));
      Eigen::Matrix3f R;
      bool rotation_ok = true;
      for (int i = 0; i < 9; ++i)
        rotation_ok = rotation_ok && static_cast<bool>(rotation >> R(i / 3, i % 3));
      if (rotation_ok) entry.model_rotation = R;
      if (!entry.model.empty() && (entry.size_m.array() > 0.f).all()) {
        catalog->entries_.push_back(std::move(entry));
      }
    }
  }
  if (catalog->entries_.empty()) {
    *why = "no furniture catalog (.sh3f) in " + folder + " (Debian package sweethome3d-furniture)";
    return nullptr;
  }
  return catalog;
}

std::vector<const FurnitureEntry*> FurnitureCatalog::Named(
    const std::vector<std::string>& names) const {
  std::vector<const FurnitureEntry*> found;
  for (const FurnitureEntry& entry : entries_) {
    if (std::find(names.begin(), names.end(), entry.name) != names.end()) found.push_back(&entry);
  }
  return found;
}

bool FurnitureCatalog::LoadMesh(const FurnitureEntry& entry, TriangleMesh* mesh,
                                std::string* why) const {
  ZipArchive zip(entry.archive);
  const std::string model = entry.model.substr(entry.model[0] == '/' ? 1 : 0);
  std::string text;
  if (!zip.ok() || !zip.Read(model, &text)) {
    *why = entry.archive + ": " + model + " cannot be read";
    return false;
  }
  const std::string folder = model.substr(0, model.rfind('/') + 1);
  std::vector<Eigen::Vector3f> positions;
  std::vector<Eigen::Vector2f> uvs;
  std::map<std::string, Material> materials;
  const Material plain;
  const Material* material = &plain;
  *mesh = TriangleMesh{};
  std::map<const Texture*, int> texture_index_of;
  std::vector<int> texture_of;
  std::vector<std::array<Eigen::Vector2f, 3>> triangle_uvs;
  std::istringstream lines(text);
  std::string line;
  while (std::getline(lines, line)) {
    std::istringstream words(line);
    std::string keyword;
    words >> keyword;
    if (keyword == "v") {
      Eigen::Vector3f p;
      words >> p.x() >> p.y() >> p.z();
      positions.push_back(p);
    } else if (keyword == "vt") {
      Eigen::Vector2f t;
      words >> t.x() >> t.y();
      uvs.push_back(t);
    } else if (keyword == "mtllib") {
      std::string file;
      std::getline(words, file);
      std::string mtl;
      if (zip.Read(folder + Trim(file), &mtl)) {
        for (auto& [name, m] : ParseMaterials(mtl, folder, &zip)) materials[name] = std::move(m);
      }
    } else if (keyword == "usemtl") {
      std::string name;
      words >> name;
      const auto it = materials.find(name);
      material = it == materials.end() ? &plain : &it->second;
    } else if (keyword == "f") {
      std::vector<int> corners;
      std::vector<Eigen::Vector2f> corner_uvs;
      bool all_uvs = true;
      std::string corner;
      while (words >> corner) {
        const std::size_t slash = corner.find('/');
        const int v = Index(corner.substr(0, slash), positions.size());
        if (v < 0) continue;
        corners.push_back(v);
        int t = -1;
        if (slash != std::string::npos) {
          const std::size_t next = corner.find('/', slash + 1);
          t = Index(corner.substr(slash + 1, next - slash - 1), uvs.size());
        }
        all_uvs = all_uvs && t >= 0;
        corner_uvs.push_back(t >= 0 ? uvs[t] : Eigen::Vector2f::Zero());
      }
      Eigen::Vector2f uv_sum = Eigen::Vector2f::Zero();
      for (const Eigen::Vector2f& uv : corner_uvs) uv_sum += uv;
      const Rgb color = ColorOf(
          *material, corner_uvs.empty() ? uv_sum : Eigen::Vector2f(uv_sum / corner_uvs.size()));
      // Textured faces are sampled per pixel by the renderer; the rest keep their colour.
      int texture_index = -1;
      if (material->texture && all_uvs) {
        const auto it = texture_index_of.find(material->texture.get());
        if (it != texture_index_of.end()) {
          texture_index = it->second;
        } else {
          texture_index = static_cast<int>(mesh->textures.size());
          texture_index_of[material->texture.get()] = texture_index;
          mesh->textures.push_back(material->texture);
        }
      }
      for (std::size_t k = 1; k + 1 < corners.size(); ++k) {
        mesh->triangles.emplace_back(corners[0], corners[k], corners[k + 1]);
        mesh->colors.push_back(color);
        texture_of.push_back(texture_index);
        triangle_uvs.push_back({corner_uvs[0], corner_uvs[k], corner_uvs[k + 1]});
      }
    }
  }
  if (!mesh->textures.empty()) {
    mesh->texture_of = std::move(texture_of);
    mesh->corner_uvs = std::move(triangle_uvs);
  }
  if (mesh->triangles.empty()) {
    *why = entry.archive + ": " + model + " has no faces";
    return false;
  }
  // Sweet Home 3D's frame: the model rotation, then y up and the front towards +z; objmap's:
  // z up and the front towards -y. Then the size of the catalog entry.
  Eigen::Matrix3f to_objmap;
  to_objmap << 1.f, 0.f, 0.f, 0.f, 0.f, -1.f, 0.f, 1.f, 0.f;
  const Eigen::Matrix3f R = to_objmap * entry.model_rotation;
  mesh->vertices.reserve(positions.size());
  for (const Eigen::Vector3f& p : positions) mesh->vertices.push_back(R * p);
  Eigen::Vector3f min, max;
  mesh->Bounds(&min, &max);
  const Eigen::Vector3f extent = (max - min).cwiseMax(1e-6f);
  const Eigen::Vector3f scale = entry.size_m.cwiseQuotient(extent);
  const Eigen::Vector3f centre(0.5f * (min.x() + max.x()), 0.5f * (min.y() + max.y()), min.z());
  for (Eigen::Vector3f& v : mesh->vertices) v = (v - centre).cwiseProduct(scale);
  return true;
}

}  // namespace objmap::sim
