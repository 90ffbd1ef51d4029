#pragma once
// The procedural stand-ins of the synthetic scenes' COCO objects, and their replacement by real
// furniture meshes. Every mesh stands on z = 0 of its own frame, centred on x = y = 0 unless
// said otherwise; fronts face -y.

#include <cstdint>
#include <string>
#include <vector>

#include "sim/scene.h"
#include "sim/sim_random.h"

namespace objmap::sim {

class FurnitureCatalog;

/// `color` with each channel moved by up to 20 levels.
[[nodiscard]] Rgb Jitter(const Rgb& color, Random* random);

/// A top of 3 cm on four legs.
[[nodiscard]] TriangleMesh TableMesh(float length, float width, float height, const Rgb& wood);
/// Seat 0.45 m high; the back is on the +y side.
[[nodiscard]] TriangleMesh ChairMesh(const Rgb& color);
/// A flat screen on a stand; the screen faces -y.
[[nodiscard]] TriangleMesh MonitorMesh(float width, float height, const Rgb& frame,
                                       const Rgb& screen);
/// A computer keyboard: a flat slab with a relief of keys (the paper's flat-keyboard case).
[[nodiscard]] TriangleMesh KeyboardMesh(const Rgb& body, const Rgb& keys);
[[nodiscard]] TriangleMesh MouseMesh(const Rgb& color);
/// A mug of 8 cm diameter, 10 cm high, with a handle on the +x side.
[[nodiscard]] TriangleMesh CupMesh(const Rgb& color);
[[nodiscard]] TriangleMesh BookMesh(float length, float width, float thickness, const Rgb& color);
/// Opened to about 105 degrees, hinged at the back (+y) edge.
[[nodiscard]] TriangleMesh LaptopMesh(const Rgb& color, const Rgb& screen);
[[nodiscard]] TriangleMesh BottleMesh(const Rgb& color);
/// A box appliance with a darker front panel (door, window) facing -y.
[[nodiscard]] TriangleMesh ApplianceMesh(float width, float depth, float height, const Rgb& body,
                                         const Rgb& front);
/// A sink basin: a rim around a recess, set into a counter top (its rim at z = 0).
[[nodiscard]] TriangleMesh SinkMesh(const Rgb& steel);
/// A pot of 30 cm with a bush of 50 cm on it.
[[nodiscard]] TriangleMesh PottedPlantMesh();

/// With a `catalog`, a real mesh of the class (or one of `mesh_names` when given) scaled into
/// `procedural`'s bounds, picked by (seed, id) so that dressing a scene moves nothing in it, and
/// its credits appended to `name`; `procedural` itself without a catalog, for a class the
/// catalog has no names for, or when no candidate loads.
[[nodiscard]] TriangleMesh DressFromCatalog(const FurnitureCatalog* catalog,
                                            const std::string& class_name,
                                            const TriangleMesh& procedural, std::uint64_t seed,
                                            int id, const std::vector<std::string>* mesh_names,
                                            std::string* name);

}  // namespace objmap::sim
