#include "core/render/embree_scene.h"

#include <limits>
#include <stdexcept>
#include <string>

namespace penumbra {

namespace {
void report_embree_error(void*, RTCError code, const char* message) {
  if (code == RTC_ERROR_NONE) return;
  // Errors during build surface through rtcGetDeviceError below; keep this quiet.
  (void)message;
}
// Embree's memory monitor: called with each allocation (bytes > 0) and release (bytes < 0).
bool count_embree_bytes(void* counter, ssize_t bytes, bool) {
  static_cast<std::atomic<int64_t>*>(counter)->fetch_add(int64_t(bytes));
  return true;  // never refuse an allocation
}
}  // namespace

EmbreeScene::EmbreeScene(const Scene& scene) : source_(&scene) {
  device_ = rtcNewDevice("threads=1,set_affinity=0");
  if (!device_) throw std::runtime_error("Embree: cannot create a device");
  rtcSetDeviceErrorFunction(device_, report_embree_error, nullptr);
  rtcSetDeviceMemoryMonitorFunction(device_, count_embree_bytes, &memory_bytes_);
  scene_ = rtcNewScene(device_);
  rtcSetSceneBuildQuality(scene_, RTC_BUILD_QUALITY_MEDIUM);

  // Scene extent sets the ray epsilon (relative, so any scene scale works).
  double extent = 0;
  for (const Vec3& p : scene.positions)
    extent = std::max({extent, std::abs(p.x), std::abs(p.y), std::abs(p.z)});
  for (const Light& light : scene.lights)
    for (const Vec3& p : {light.centroid})
      extent = std::max({extent, std::abs(p.x), std::abs(p.y), std::abs(p.z)});
  ray_epsilon_ = std::max(1e-6, extent * 2e-5);

  if (scene.triangle_count() > 0) {
    RTCGeometry geometry = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_TRIANGLE);
    auto* vertices = static_cast<float*>(
        rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                3 * sizeof(float), scene.positions.size()));
    for (size_t i = 0; i < scene.positions.size(); ++i) {
      vertices[i * 3 + 0] = float(scene.positions[i].x);
      vertices[i * 3 + 1] = float(scene.positions[i].y);
      vertices[i * 3 + 2] = float(scene.positions[i].z);
    }
    auto* indices = static_cast<unsigned*>(
        rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                3 * sizeof(unsigned), scene.triangle_count()));
    std::copy(scene.indices.begin(), scene.indices.end(), indices);
    rtcCommitGeometry(geometry);
    rtcAttachGeometry(scene_, geometry);
    rtcReleaseGeometry(geometry);
  }
  rtcCommitScene(scene_);
  RTCError error = rtcGetDeviceError(device_);
  if (error != RTC_ERROR_NONE)
    throw std::runtime_error("Embree: scene build failed (error " + std::to_string(int(error)) +
                             ")");
}

EmbreeScene::~EmbreeScene() {
  if (scene_) rtcReleaseScene(scene_);
  if (device_) rtcReleaseDevice(device_);
}

std::optional<SurfaceHit> EmbreeScene::intersect(const Vec3& origin, const Vec3& direction,
                                                 double t_max) const {
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRayHit rayhit;
  rayhit.ray.org_x = float(origin.x);
  rayhit.ray.org_y = float(origin.y);
  rayhit.ray.org_z = float(origin.z);
  rayhit.ray.dir_x = float(direction.x);
  rayhit.ray.dir_y = float(direction.y);
  rayhit.ray.dir_z = float(direction.z);
  rayhit.ray.tnear = 0.0f;
  rayhit.ray.tfar = float(std::min(t_max, double(std::numeric_limits<float>::max())));
  rayhit.ray.mask = 0xFFFFFFFF;
  rayhit.ray.flags = 0;
  rayhit.ray.time = 0;
  rayhit.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rayhit.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  rtcIntersect1(scene_, &context, &rayhit);
  if (rayhit.hit.geomID == RTC_INVALID_GEOMETRY_ID) return std::nullopt;

  SurfaceHit hit;
  hit.distance = rayhit.ray.tfar;
  hit.triangle = rayhit.hit.primID;
  // Recompute position and normal in double from the triangle (more accurate than Ng in float).
  const uint32_t* tri = &source_->indices[size_t(hit.triangle) * 3];
  const Vec3& p0 = source_->positions[tri[0]];
  const Vec3& p1 = source_->positions[tri[1]];
  const Vec3& p2 = source_->positions[tri[2]];
  double u = rayhit.hit.u, v = rayhit.hit.v;
  hit.barycentric = {u, v};
  hit.position = p0 * (1 - u - v) + p1 * u + p2 * v;
  Vec3 n = cross(p1 - p0, p2 - p0);
  double len = length(n);
  hit.geometric_normal = len > 0 ? n / len : Vec3{0, 0, 1};
  return hit;
}

bool EmbreeScene::occluded(const Vec3& from, const Vec3& normal, const Vec3& to) const {
  Vec3 origin = from + normal * ray_epsilon_;
  Vec3 d = to - origin;
  double distance = length(d);
  if (!(distance > 2 * ray_epsilon_)) return false;
  Vec3 direction = d / distance;
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRay ray;
  ray.org_x = float(origin.x);
  ray.org_y = float(origin.y);
  ray.org_z = float(origin.z);
  ray.dir_x = float(direction.x);
  ray.dir_y = float(direction.y);
  ray.dir_z = float(direction.z);
  ray.tnear = 0.0f;
  ray.tfar = float(distance - ray_epsilon_);
  ray.mask = 0xFFFFFFFF;
  ray.flags = 0;
  ray.time = 0;
  rtcOccluded1(scene_, &context, &ray);
  return ray.tfar < 0.0f;  // Embree sets tfar to -inf on a hit
}

}  // namespace penumbra
