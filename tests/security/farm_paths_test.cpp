// The coordinator never opens a path a client names: scenes arrive as uploaded content and the
// OBJ files a scene names are looked up in its package only (an absolute path, a path leaving the
// scene's folder, or a file missing from the package is refused even when the file exists on the
// coordinator's disk). The worker's scene cache is addressed by content hash only: a task whose
// scene hash is a path, not lowercase hex, or names a scene whose content hashes differently is
// refused (FailTask) without fetching or writing anything outside its cache, a task whose tile
// leaves the image is refused, and a good scene is cached under its hash. The worker runs against a
// fake coordinator in this process.
#if __has_include("penumbra/v1/farm.pb.h")
#include <grpcpp/server.h>
#include <grpcpp/server_builder.h>
#include <gtest/gtest.h>

#include "proto/support/scene_chunks.h"
#include "security_test_support.h"

namespace penumbra::farm {
namespace {

using namespace std::chrono_literals;
using grpc::StatusCode;
using testing::CoordinatorProcess;

const char* kTriangleObj = "v -1 0 -1\nv 1 0 -1\nv 0 0.5 -1\nf 1 2 3\n";

// The small test scene with one OBJ shape naming `obj_path`.
std::string scene_with_obj(const std::string& obj_path) {
  std::string json = testing::small_scene_json(32, 24);
  const std::string shapes = "\"shapes\": [";
  json.insert(json.find(shapes) + shapes.size(), "\n    { \"type\": \"obj\", \"file\": \"" +
                                                     obj_path + "\", \"material\": \"white\" },");
  return json;
}

TEST(FarmPaths, CoordinatorOpensNoPathAClientNames) {
  auto dir = testing::fresh_directory("paths");
  // The files exist where a careless coordinator would look for them.
  std::ofstream(dir / "outside.obj") << kTriangleObj;
  std::ofstream(dir / "mesh.obj") << kTriangleObj;
  CoordinatorProcess coordinator(dir / "data");
  std::ofstream(dir / "data" / "mesh.obj") << kTriangleObj;
  FarmClient client(coordinator.address());

  auto submit = [&](const std::string& obj_path, bool include_file) {
    v1::JobSpec spec = testing::job_spec(testing::write_scene(dir, 32, 24), "sa", 4, 1);
    v1::ScenePackage& package = *spec.mutable_scene();
    package.set_scene_json(scene_with_obj(obj_path));
    package.set_source_name((dir / "scene.json").string());
    package.mutable_files()->clear();
    if (include_file) (*package.mutable_files())[obj_path] = kTriangleObj;
    try {
      client.submit(spec);
    } catch (const FarmCallError& error) {
      return std::make_pair(error.code(), std::string(error.what()));
    }
    return std::make_pair(StatusCode::OK, std::string());
  };
  // The package carries the file: accepted (the scene is good).
  EXPECT_EQ(submit("mesh.obj", true).first, StatusCode::OK);
  // Not in the package: refused although mesh.obj sits beside the named source and in the
  // coordinator's data folder.
  auto [missing_code, missing] = submit("mesh.obj", false);
  EXPECT_EQ(missing_code, StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(missing.find("not in the scene package"), std::string::npos) << missing;
  // Absolute and escaping paths: refused lexically, even when the package carries them.
  const std::string absolute = (dir / "outside.obj").string();
  EXPECT_EQ(submit(absolute, false).first, StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(submit(absolute, true).first, StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(submit("../outside.obj", true).first, StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(submit("sub/../../outside.obj", true).first, StatusCode::INVALID_ARGUMENT);
  // A scene hash is a key, not a path.
  v1::JobSpec by_hash = testing::job_spec(testing::write_scene(dir, 32, 24), "sa", 4, 1);
  by_hash.set_scene_hash("../../../../etc/passwd");
  EXPECT_EQ(testing::code_of([&] { client.submit(by_hash); }), StatusCode::NOT_FOUND);
  EXPECT_EQ(client.list().size(), 1u);
}

// A fake coordinator's workers service: hands out the tasks it is given once, serves one scene
// package, and records what the worker asks and reports.
class FakeWorkersService final : public v1::Workers::Service {
 public:
  std::mutex mutex;
  std::vector<v1::Task> to_lease;
  v1::ScenePackage package;  // served for any well-formed hash asked
  std::vector<std::string> scene_requests;
  std::map<std::string, std::string> failures;  // attempt token -> error
  std::vector<std::string> completions;         // attempt tokens

  grpc::Status Register(grpc::ServerContext*, const v1::RegisterRequest*,
                        v1::RegisterResponse* response) override {
    response->set_worker_id("w-fake");
    response->set_lease_seconds(60);
    response->set_heartbeat_seconds(1);
    return grpc::Status::OK;
  }
  grpc::Status Heartbeat(grpc::ServerContext*, const v1::HeartbeatRequest*,
                         v1::HeartbeatResponse*) override {
    return grpc::Status::OK;
  }
  grpc::Status LeaseTasks(grpc::ServerContext*, const v1::LeaseTasksRequest* request,
                          v1::LeaseTasksResponse* response) override {
    std::lock_guard lock(mutex);
    while (!to_lease.empty() && uint32_t(response->tasks_size()) < request->max_tasks()) {
      *response->add_tasks() = to_lease.front();
      to_lease.erase(to_lease.begin());
    }
    return grpc::Status::OK;
  }
  grpc::Status GetScene(grpc::ServerContext*, const v1::GetSceneRequest* request,
                        v1::ScenePackage* response) override {
    std::lock_guard lock(mutex);
    scene_requests.push_back(request->scene_hash());
    *response = package;
    return grpc::Status::OK;
  }
  // The package in chunks, under whatever hash is asked for (a coordinator that lies: the
  // worker must find out from the content).
  grpc::Status GetSceneManifest(grpc::ServerContext*, const v1::GetSceneRequest* request,
                                v1::SceneManifest* response) override {
    std::lock_guard lock(mutex);
    scene_requests.push_back(request->scene_hash());
    *response = make_scene_manifest(request->scene_hash(), serialize_package(package), 4096);
    return grpc::Status::OK;
  }
  grpc::Status GetSceneChunk(grpc::ServerContext*, const v1::GetSceneChunkRequest* request,
                             v1::SceneChunk* response) override {
    std::lock_guard lock(mutex);
    scene_requests.push_back(request->scene_hash());
    const std::string bytes = serialize_package(package);
    response->set_index(request->index());
    response->set_data(bytes.substr(size_t(request->index()) * 4096, 4096));
    return grpc::Status::OK;
  }
  grpc::Status CompleteTask(grpc::ServerContext*, const v1::CompleteTaskRequest* request,
                            v1::CompleteTaskResponse* response) override {
    std::lock_guard lock(mutex);
    completions.push_back(request->attempt_token());
    response->set_accepted(true);
    return grpc::Status::OK;
  }
  grpc::Status FailTask(grpc::ServerContext*, const v1::FailTaskRequest* request,
                        v1::FailTaskResponse*) override {
    std::lock_guard lock(mutex);
    failures[request->attempt_token()] = request->error();
    return grpc::Status::OK;
  }
};

v1::Task task(const std::string& token, const std::string& scene_hash) {
  v1::Task task;
  task.set_job_id("job-1");
  task.set_task_index(std::hash<std::string>()(token) % 1000);
  task.set_attempt_token(token);
  task.set_scene_hash(scene_hash);
  task.set_method("sa");
  task.set_sampler("stratified");
  task.set_seed(1);
  task.mutable_tile()->set_x0(0);
  task.mutable_tile()->set_y0(0);
  task.mutable_tile()->set_x1(8);
  task.mutable_tile()->set_y1(8);
  task.set_pass_begin(0);
  task.set_pass_end(1);
  return task;
}

TEST(WorkerCache, AddressedByContentHashOnly) {
  auto dir = testing::fresh_directory("cache");
  std::string scene_path = testing::write_scene(dir, 32, 24);
  v1::ScenePackage package = pack_scene_file(scene_path);
  const std::string hash = parse_wire_package(package).content_hash;
  ASSERT_EQ(hash.size(), 64u);

  FakeWorkersService service;
  service.package = package;
  const std::string escape =
      "../../../../../../tmp/penumbra-cache-escape-" + std::to_string(::getpid());
  std::string upper = hash;
  for (char& c : upper) c = char(std::toupper(static_cast<unsigned char>(c)));
  const std::string other_hash(64, 'a');     // well formed; the package served hashes differently
  v1::Task outside = task("outside", hash);  // a tile past the 32x24 image
  outside.mutable_tile()->set_x1(4096);
  service.to_lease = {task("escape", escape),
                      task("upper", upper),
                      task("dot", "."),
                      task("mismatch", other_hash),
                      outside,
                      task("good", hash)};
  grpc::ServerBuilder builder;
  int port = 0;
  builder.AddListeningPort("127.0.0.1:0", grpc::InsecureServerCredentials(), &port);
  builder.RegisterService(&service);
  std::unique_ptr<grpc::Server> server = builder.BuildAndStart();
  ASSERT_TRUE(server && port > 0);

  auto cache = dir / "cache-w";
  auto worker = testing::start_worker("127.0.0.1:" + std::to_string(port), dir, "w");
  auto deadline = std::chrono::steady_clock::now() + 60s;
  while (std::chrono::steady_clock::now() < deadline) {
    {
      std::lock_guard lock(service.mutex);
      if (service.failures.size() + service.completions.size() >= 6) break;
    }
    std::this_thread::sleep_for(50ms);
  }
  worker.reset();
  server->Shutdown(std::chrono::system_clock::now() + 2s);

  std::lock_guard lock(service.mutex);
  for (const char* refused : {"escape", "upper", "dot", "mismatch", "outside"})
    EXPECT_TRUE(service.failures.count(refused)) << refused << " was not refused";
  EXPECT_NE(service.failures["mismatch"].find(other_hash), std::string::npos)
      << service.failures["mismatch"];
  ASSERT_EQ(service.completions, std::vector<std::string>{"good"})
      << "the good task did not complete; see " << (dir / "w.log");
  // Only well-formed hashes were ever asked for.
  for (const std::string& asked : service.scene_requests)
    EXPECT_TRUE(asked == hash || asked == other_hash) << "asked for scene \"" << asked << "\"";
  EXPECT_FALSE(std::filesystem::exists("/tmp/penumbra-cache-escape-" + std::to_string(::getpid())));
  EXPECT_FALSE(
      std::filesystem::exists("/tmp/penumbra-cache-escape-" + std::to_string(::getpid()) + ".pb"));
  // The cache holds the good scene under its hash, and nothing else.
  std::vector<std::string> cached;
  if (std::filesystem::exists(cache))
    for (const auto& entry : std::filesystem::recursive_directory_iterator(cache))
      if (entry.is_regular_file()) cached.push_back(entry.path().lexically_relative(cache));
  EXPECT_EQ(cached, std::vector<std::string>{"scenes/" + hash + ".pb"});
}

}  // namespace
}  // namespace penumbra::farm
#else
#include <gtest/gtest.h>
TEST(FarmNotBuilt, Skipped) {
  GTEST_SKIP() << "configured with PENUMBRA_FARM=OFF";
}
#endif
