// The embedded farm (what `penumbra demo` runs): a coordinator and workers in this process on a
// loopback port; its films are bit-identical to a local render.
// Built only with the farm (PENUMBRA_FARM=ON); otherwise the program reports a skipped test.
#if __has_include("penumbra/v1/farm.pb.h")
#include "server/embedded_farm.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

#include "farm_test_support.h"
#include "proto/support/scene_chunks.h"
#include "proto/support/scene_packing.h"

namespace penumbra::farm {
namespace {

TEST(EmbeddedFarm, RunsJobsAndReturnsTheirFilms) {
  auto dir = testing::fresh_directory("embedded");
  std::string scene = testing::write_scene(dir, 64, 48);
  EmbeddedFarmOptions options;
  options.workers = 2;
  options.threads_per_worker = 1;
  EmbeddedFarm farm(options);
  int events = 0;
  Film film = farm.run(testing::job_spec(scene, "sa", 12, 4, 32, 4),
                       [&](const v1::JobStatus&) { ++events; });
  EXPECT_GE(events, 1);
  Film local = testing::render_locally(scene, "sa", "stratified", 12, 4);
  EXPECT_TRUE(testing::same_bits(film.color, local.color));
  EXPECT_TRUE(testing::same_bits(film.variance, local.variance));
  // A failing job is reported, not hidden.
  EXPECT_THROW(farm.run(testing::job_spec(scene, "no-such-method", 4, 1)), FarmCallError);
  std::filesystem::remove_all(dir);
}

// A pbrt-v3 scene whose PLY mesh makes the package larger than gRPC's default 4 MiB message
// limit: a wavy n x n vertex grid (binary PLY, 12 bytes a vertex, 13 a triangle) under a quad
// light with a small occluder between them.
std::string write_big_pbrt_scene(const std::filesystem::path& dir, int n) {
  std::filesystem::create_directories(dir / "models");
  std::string ply = "ply\nformat binary_little_endian 1.0\nelement vertex " +
                    std::to_string(n * n) +
                    "\nproperty float x\nproperty float y\nproperty float z\nelement face " +
                    std::to_string(2 * (n - 1) * (n - 1)) +
                    "\nproperty list uint8 int vertex_indices\nend_header\n";
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const float x = -2.0f + 4.0f * float(i) / float(n - 1);
      const float y = -2.0f + 4.0f * float(j) / float(n - 1);
      const float xyz[3] = {x, y, 0.05f * std::sin(7.0f * x) * std::cos(5.0f * y)};
      ply.append(reinterpret_cast<const char*>(xyz), sizeof xyz);
    }
  auto face = [&](int32_t a, int32_t b, int32_t c) {
    ply.push_back(char(3));
    for (int32_t v : {a, b, c}) ply.append(reinterpret_cast<const char*>(&v), 4);
  };
  for (int j = 0; j + 1 < n; ++j)
    for (int i = 0; i + 1 < n; ++i) {
      const int32_t v = j * n + i;
      face(v, v + 1, v + n + 1);
      face(v, v + n + 1, v + n);
    }
  std::ofstream(dir / "models" / "grid.ply", std::ios::binary) << ply;
  const auto path = dir / "big.pbrt";
  std::ofstream(path) << R"(LookAt 0 -3 3  0 0 0  0 0 1
Camera "perspective" "float fov" [ 50 ]
Film "image" "integer xresolution" [ 40 ] "integer yresolution" [ 30 ]
WorldBegin
Material "matte" "rgb Kd" [ 0.6 0.5 0.4 ]
Shape "plymesh" "string filename" "models/grid.ply"
Shape "trianglemesh" "integer indices" [ 0 1 2 0 2 3 ]
  "point P" [ -0.3 -0.2 1  0.3 -0.2 1  0.3 0.2 1  -0.3 0.2 1 ]
AttributeBegin
  AreaLightSource "diffuse" "rgb L" [ 4 4 4 ]
  Shape "quad" "point o" [ -0.5 0.5 2 ] "vector u" [ 1 0 0 ] "vector v" [ 0 -1 0 ]
AttributeEnd
WorldEnd
)";
  return path.string();
}

// A scene of more than 4 MiB travels in chunks of 1 MiB (no message near the 4 MiB default
// limit); an upload cut short after two chunks resumes with the others only; the job renders on
// two workers bit for bit as locally.
TEST(EmbeddedFarm, BigSceneUploadsInChunksResumesAndRendersAsLocally) {
  auto dir = testing::fresh_directory("embedded-big");
  const std::string path = write_big_pbrt_scene(dir, 360);
  const v1::ScenePackage package = pack_scene_file(path);
  const std::string hash = parse_wire_package(package).content_hash;
  const size_t bytes = package.ByteSizeLong();
  ASSERT_GT(bytes, size_t(4) << 20);
  EmbeddedFarmOptions two_workers;
  two_workers.workers = 2;
  EmbeddedFarm farm(two_workers);

  SceneUploadOptions cut_short;
  cut_short.stop_after_chunks = 2;
  SceneUploadResult first = farm.client().upload_scene(package, hash, cut_short);
  EXPECT_FALSE(first.complete);
  EXPECT_EQ(first.chunks_sent, 2u);
  const uint32_t chunks = first.chunks_total;
  EXPECT_EQ(chunks, (bytes + (1u << 20) - 1) >> 20);
  // Not stored yet: a job naming it is refused.
  v1::JobSpec spec = testing::job_spec(path, "sa", 4, 3, 16, 2);
  spec.set_scene_hash(hash);
  try {
    farm.submit(spec);
    ADD_FAILURE() << "a job of a half-uploaded scene was accepted";
  } catch (const FarmCallError& error) {
    EXPECT_EQ(error.code(), grpc::StatusCode::NOT_FOUND) << error.what();
  }
  SceneUploadResult resumed = farm.client().upload_scene(package, hash);
  EXPECT_TRUE(resumed.complete);
  EXPECT_FALSE(resumed.already_stored);
  EXPECT_EQ(resumed.chunks_sent, chunks - 2);  // the first two were kept
  SceneUploadResult again = farm.client().upload_scene(package, hash);
  EXPECT_TRUE(again.already_stored);
  EXPECT_EQ(again.chunks_sent, 0u);

  Film film = farm.run(spec);
  Film local = testing::render_locally(path, "sa", "stratified", 4, 3);
  EXPECT_TRUE(testing::same_bits(film.color, local.color));
  EXPECT_TRUE(testing::same_bits(film.variance, local.variance));
  std::filesystem::remove_all(dir);
}

// Over the coordinator's scene-size limit: RESOURCE_EXHAUSTED naming the size and the limit,
// before any chunk is sent; a chunk that is not what its manifest says: INVALID_ARGUMENT.
TEST(EmbeddedFarm, SceneUploadsOverTheLimitOrWithBadChunksAreRefused) {
  auto dir = testing::fresh_directory("embedded-limit");
  const std::string path = testing::write_scene(dir, 32, 24);
  const v1::ScenePackage package = pack_scene_file(path);
  const std::string hash = parse_wire_package(package).content_hash;
  const std::string bytes = serialize_package(package);
  EmbeddedFarmOptions limited;
  limited.workers = 1;
  limited.max_scene_bytes = bytes.size() / 2;
  EmbeddedFarm farm(limited);
  SceneUploadOptions small_chunks;
  small_chunks.chunk_bytes = 4096;
  try {
    farm.client().upload_scene(package, hash, small_chunks);
    ADD_FAILURE() << "an upload over the limit was accepted";
  } catch (const FarmCallError& error) {
    EXPECT_EQ(error.code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
    EXPECT_NE(std::string(error.what())
                  .find("scene package of " + std::to_string(bytes.size()) +
                        " bytes (0.0 MiB) exceeds the coordinator's scene-size limit of " +
                        std::to_string(bytes.size() / 2) + " bytes"),
              std::string::npos)
        << error.what();
  }
  // The same limit holds for a package inside a job.
  try {
    farm.submit(testing::job_spec(path, "sa", 1, 1));
    ADD_FAILURE() << "an inline package over the limit was accepted";
  } catch (const FarmCallError& error) {
    EXPECT_EQ(error.code(), grpc::StatusCode::RESOURCE_EXHAUSTED) << error.what();
  }

  // A chunk whose bytes differ from its manifest's hash, straight on the stream.
  limited.max_scene_bytes = size_t(1) << 20;
  EmbeddedFarm open_farm(limited);
  v1::SceneManifest manifest = make_scene_manifest(hash, bytes, 4096);
  grpc::ClientContext context;
  v1::SceneUploadState state;
  auto writer = open_farm.client().stub().UploadScene(&context, &state);
  v1::SceneUploadMessage message;
  *message.mutable_manifest() = manifest;
  writer->Write(message);
  message.mutable_chunk()->set_index(0);
  std::string tampered = bytes.substr(0, scene_chunk_size(manifest, 0));
  tampered[0] ^= 1;
  message.mutable_chunk()->set_data(tampered);
  writer->Write(message);
  writer->WritesDone();
  grpc::Status status = writer->Finish();
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(status.error_message(), "chunk 0: its SHA-256 differs from the manifest's");
  // A manifest whose scene hash is not the package's: refused once assembled, not stored.
  const std::string other(64, 'a');
  try {
    open_farm.client().upload_scene(package, other, small_chunks);
    ADD_FAILURE() << "a package under another scene's hash was accepted";
  } catch (const FarmCallError& error) {
    EXPECT_EQ(error.code(), grpc::StatusCode::INVALID_ARGUMENT);
    EXPECT_EQ(std::string(error.what()), "INVALID_ARGUMENT: manifest.scene_hash: " + other +
                                             " is not the uploaded scene's content hash " + hash);
  }
  EXPECT_TRUE(open_farm.client().upload_scene(package, hash, small_chunks).complete);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace penumbra::farm
#else
#include <gtest/gtest.h>
TEST(FarmNotBuilt, Skipped) {
  GTEST_SKIP() << "configured with PENUMBRA_FARM=OFF";
}
#endif
