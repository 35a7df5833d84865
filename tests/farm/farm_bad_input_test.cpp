// Bad input: each gets the fitting gRPC status and the coordinator keeps serving.
// Built only with the farm (PENUMBRA_FARM=ON); otherwise the program reports a skipped test.
#if __has_include("penumbra/v1/farm.pb.h")
#include <grpcpp/generic/generic_stub.h>
#include <gtest/gtest.h>

#include <cmath>
#include <condition_variable>
#include <mutex>

#include "core/image/metrics.h"
#include "farm_test_support.h"
#include "penumbra/version.h"

namespace penumbra::farm {
namespace {

using namespace std::chrono_literals;
using testing::CoordinatorProcess;

grpc::StatusCode submit_code(FarmClient& client, const v1::JobSpec& spec, std::string* message) {
  try {
    client.submit(spec);
    return grpc::StatusCode::OK;
  } catch (const FarmCallError& error) {
    *message = error.what();
    return error.code();
  }
}

TEST(FarmBadInput, BadInputGetsFittingStatusesAndTheCoordinatorKeepsServing) {
  auto dir = testing::fresh_directory("bad-input");
  std::string scene = testing::write_scene(dir, 64, 48);
  CoordinatorProcess coordinator(dir / "data", 0, {"--max-scene-mib", "1"});
  FarmClient client(coordinator.address());
  std::string message;

  v1::JobSpec malformed = testing::job_spec(scene, "sa", 4, 1);
  malformed.mutable_scene()->set_scene_json(testing::small_scene_json(64, 48).replace(
      testing::small_scene_json(64, 48).find("\"radiance\": [5, 5, 5]"), 22,
      "\"radiance\": [5, -5]"));
  EXPECT_EQ(submit_code(client, malformed, &message), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(message.find("$.lights[0].radiance"), std::string::npos) << message;

  malformed.mutable_scene()->set_scene_json("{ not json");
  EXPECT_EQ(submit_code(client, malformed, &message), grpc::StatusCode::INVALID_ARGUMENT);

  v1::JobSpec unknown_method = testing::job_spec(scene, "sparkle", 4, 1);
  EXPECT_EQ(submit_code(client, unknown_method, &message), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(message.find("method"), std::string::npos) << message;

  v1::JobSpec zero = testing::job_spec(scene, "sa", 4, 1);
  zero.set_spp(0);
  EXPECT_EQ(submit_code(client, zero, &message), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(message.find("spp"), std::string::npos) << message;
  zero.set_compute_seconds(0);
  EXPECT_EQ(submit_code(client, zero, &message), grpc::StatusCode::INVALID_ARGUMENT);

  v1::JobSpec oversized = testing::job_spec(scene, "sa", 4, 1);
  (*oversized.mutable_scene()->mutable_files())["padding.obj"] = std::string(2 << 20, '#');
  EXPECT_EQ(submit_code(client, oversized, &message), grpc::StatusCode::RESOURCE_EXHAUSTED)
      << message;

  v1::JobSpec unknown_hash;
  unknown_hash.set_scene_hash(std::string(64, 'a'));
  unknown_hash.set_method("sa");
  unknown_hash.set_spp(4);
  EXPECT_EQ(submit_code(client, unknown_hash, &message), grpc::StatusCode::NOT_FOUND);

  v1::JobSpec unknown_reference = testing::job_spec(scene, "sa", 4, 1);
  unknown_reference.set_reference_job("job-999");
  EXPECT_EQ(submit_code(client, unknown_reference, &message), grpc::StatusCode::NOT_FOUND);

  for (const auto& call : std::vector<std::function<void()>>{
           [&] { client.status("job-42"); }, [&] { client.cancel("job-42"); },
           [&] { client.fetch("job-42"); }, [&] { client.status("nonsense"); }}) {
    try {
      call();
      ADD_FAILURE() << "an unknown job was found";
    } catch (const FarmCallError& error) {
      EXPECT_EQ(error.code(), grpc::StatusCode::NOT_FOUND) << error.what();
    }
  }

  // A worker whose build would render different bits, or of another protocol, is refused.
  auto workers = v1::Workers::NewStub(make_farm_channel(coordinator.address()));
  v1::RegisterRequest registration;
  registration.set_name("stranger");
  registration.set_threads(1);
  registration.set_build_flavour("GNU-1.0-vax-Debug-sanitize=OFF-v0.0.1");
  registration.set_protocol_version(v1::PROTOCOL_VERSION_CURRENT);
  v1::RegisterResponse registered;
  {
    grpc::ClientContext context;
    grpc::Status status = workers->Register(&context, registration, &registered);
    EXPECT_EQ(status.error_code(), grpc::StatusCode::FAILED_PRECONDITION);
    EXPECT_NE(status.error_message().find("different bits"), std::string::npos);
  }
  registration.set_build_flavour(kBuildFlavour);
  registration.set_protocol_version(v1::PROTOCOL_VERSION_UNSPECIFIED);
  {
    grpc::ClientContext context;
    EXPECT_EQ(workers->Register(&context, registration, &registered).error_code(),
              grpc::StatusCode::FAILED_PRECONDITION);
  }
  {
    v1::HeartbeatRequest heartbeat;
    heartbeat.set_worker_id("w999-ghost");
    v1::HeartbeatResponse response;
    grpc::ClientContext context;
    EXPECT_EQ(workers->Heartbeat(&context, heartbeat, &response).error_code(),
              grpc::StatusCode::NOT_FOUND);
  }

  // Still serving: a good job is accepted and the health service says SERVING.
  auto good = client.submit(testing::job_spec(scene, "sa", 4, 1));
  EXPECT_EQ(client.status(good.job_id()).state(), v1::JOB_STATE_QUEUED);
  grpc::GenericStub generic(make_farm_channel(coordinator.address()));
  grpc::ClientContext context;
  grpc::ByteBuffer request_bytes;  // an empty HealthCheckRequest: the whole server
  grpc::Slice empty("", 0);
  request_bytes = grpc::ByteBuffer(&empty, 1);
  std::mutex mutex;
  std::condition_variable done;
  bool finished = false;
  grpc::Status health_status;
  grpc::ByteBuffer response_bytes;
  grpc::StubOptions options;
  generic.UnaryCall(&context, "/grpc.health.v1.Health/Check", options, &request_bytes,
                    &response_bytes, [&](grpc::Status status) {
                      std::lock_guard lock(mutex);
                      health_status = status;
                      finished = true;
                      done.notify_all();
                    });
  std::unique_lock lock(mutex);
  ASSERT_TRUE(done.wait_for(lock, 10s, [&] { return finished; }));
  ASSERT_TRUE(health_status.ok()) << health_status.error_message();
  std::vector<grpc::Slice> slices;
  ASSERT_TRUE(response_bytes.Dump(&slices).ok());
  std::string response;
  for (const auto& slice : slices)
    response.append(reinterpret_cast<const char*>(slice.begin()), slice.size());
  EXPECT_EQ(response, std::string("\x08\x01", 2)) << "health status should be SERVING (1)";
}

}  // namespace
}  // namespace penumbra::farm
#else
#include <gtest/gtest.h>
TEST(FarmNotBuilt, Skipped) {
  GTEST_SKIP() << "configured with PENUMBRA_FARM=OFF";
}
#endif
