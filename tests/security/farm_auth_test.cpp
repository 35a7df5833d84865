// Token roles against a real coordinator (--tokens-file, plaintext on loopback): a client token
// cannot lease tasks, a worker token cannot submit, cancel or fetch, no or an unknown token is
// UNAUTHENTICATED, health stays open, a refused call has no effect, the owner of a job is the
// authenticated caller, a worker with a worker token renders a job bit for bit and one with a
// client token is refused; per-client limits on unfinished jobs and on scene size.
#if __has_include("penumbra/v1/farm.pb.h")
#include <gtest/gtest.h>

#include "penumbra/version.h"
#include "proto/support/batch_client.h"
#include "security_test_support.h"

namespace penumbra::farm {
namespace {

using namespace std::chrono_literals;
using grpc::StatusCode;
using testing::code_of;
using testing::connection_to;
using testing::CoordinatorProcess;

class FarmAuth : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new std::filesystem::path(testing::fresh_directory("auth"));
    scene_ = new std::string(testing::write_scene(*dir_, 32, 24));
    auto tokens = testing::write_tokens_file(*dir_);
    coordinator_ = new CoordinatorProcess(*dir_ / "data", 0, {"--tokens-file", tokens.string()});
  }
  static void TearDownTestSuite() {
    delete coordinator_;
    delete scene_;
    delete dir_;
  }
  static FarmClient client(const std::string& token) {
    return FarmClient(connection_to(coordinator_->address(), token));
  }
  static std::unique_ptr<v1::Workers::Stub> workers(const std::string& token) {
    return v1::Workers::NewStub(make_farm_channel(connection_to(coordinator_->address(), token)));
  }
  static StatusCode register_code(const std::string& token) {
    v1::RegisterRequest request;
    request.set_name("probe");
    request.set_threads(1);
    request.set_version(kVersion);
    request.set_build_flavour(kBuildFlavour);
    request.set_protocol_version(v1::PROTOCOL_VERSION_CURRENT);
    v1::RegisterResponse response;
    return workers(token)
        ->Register(testing::short_context().get(), request, &response)
        .error_code();
  }
  static StatusCode lease_code(const std::string& token) {
    v1::LeaseTasksRequest request;
    request.set_worker_id("w1");
    request.set_max_tasks(4);
    v1::LeaseTasksResponse response;
    return workers(token)
        ->LeaseTasks(testing::short_context().get(), request, &response)
        .error_code();
  }

  static std::filesystem::path* dir_;
  static std::string* scene_;
  static CoordinatorProcess* coordinator_;
};
std::filesystem::path* FarmAuth::dir_ = nullptr;
std::string* FarmAuth::scene_ = nullptr;
CoordinatorProcess* FarmAuth::coordinator_ = nullptr;

TEST_F(FarmAuth, ClientTokenCannotActAsWorker) {
  EXPECT_EQ(register_code(testing::kAliceToken), StatusCode::PERMISSION_DENIED);
  EXPECT_EQ(lease_code(testing::kAliceToken), StatusCode::PERMISSION_DENIED);
  v1::GetSceneRequest request;
  request.set_scene_hash(std::string(64, 'a'));
  v1::ScenePackage package;
  grpc::Status scene =
      workers(testing::kAliceToken)->GetScene(testing::short_context().get(), request, &package);
  EXPECT_EQ(scene.error_code(), StatusCode::PERMISSION_DENIED);
  // The refusal says why, and never echoes the token.
  EXPECT_NE(scene.error_message().find("needs role worker"), std::string::npos)
      << scene.error_message();
  EXPECT_EQ(scene.error_message().find(testing::kAliceToken), std::string::npos);
  // The same token may use the jobs API.
  FarmClient alice = client(testing::kAliceToken);
  EXPECT_EQ(code_of([&] { alice.list(); }), StatusCode::OK);
}

TEST_F(FarmAuth, WorkerTokenCannotSubmitCancelOrFetch) {
  FarmClient alice = client(testing::kAliceToken);
  std::string job = alice.submit(testing::job_spec(*scene_, "sa", 4, 1)).job_id();
  size_t jobs_before = alice.list().size();

  FarmClient worker = client(testing::kWorkerToken);
  EXPECT_EQ(code_of([&] { worker.submit(testing::job_spec(*scene_, "sa", 4, 2)); }),
            StatusCode::PERMISSION_DENIED);
  EXPECT_EQ(code_of([&] { worker.cancel(job); }), StatusCode::PERMISSION_DENIED);
  EXPECT_EQ(code_of([&] { worker.fetch(job); }), StatusCode::PERMISSION_DENIED);
  EXPECT_EQ(code_of([&] { worker.status(job); }), StatusCode::PERMISSION_DENIED);
  EXPECT_EQ(code_of([&] { worker.wait(job, 10s); }), StatusCode::PERMISSION_DENIED);
  // Nothing happened: no job was added, the job was not cancelled.
  EXPECT_EQ(alice.list().size(), jobs_before);
  EXPECT_EQ(alice.status(job).state(), v1::JOB_STATE_QUEUED);
  // The worker token is good for the workers API.
  EXPECT_EQ(register_code(testing::kWorkerToken), StatusCode::OK);
  alice.cancel(job);
}

TEST_F(FarmAuth, NoOrUnknownTokenIsUnauthenticatedAndHealthStaysOpen) {
  FarmClient anonymous = client("");
  EXPECT_EQ(code_of([&] { anonymous.list(); }), StatusCode::UNAUTHENTICATED);
  EXPECT_EQ(code_of([&] { anonymous.submit(testing::job_spec(*scene_, "sa", 4, 1)); }),
            StatusCode::UNAUTHENTICATED);
  EXPECT_EQ(register_code(""), StatusCode::UNAUTHENTICATED);
  FarmClient stranger = client("stranger-0123456789abcdef");
  EXPECT_EQ(code_of([&] { stranger.list(); }), StatusCode::UNAUTHENTICATED);
  EXPECT_EQ(code_of([&] { stranger.fetch("job-1"); }), StatusCode::UNAUTHENTICATED);
  EXPECT_EQ(lease_code("stranger-0123456789abcdef"), StatusCode::UNAUTHENTICATED);
  // A token of the right text in the wrong scheme is no token.
  grpc::ClientContext context;
  context.AddMetadata("authorization", std::string("Basic ") + testing::kAliceToken);
  v1::ListJobsResponse response;
  EXPECT_EQ(v1::Jobs::NewStub(make_farm_channel(coordinator_->address()))
                ->ListJobs(&context, v1::ListJobsRequest(), &response)
                .error_code(),
            StatusCode::UNAUTHENTICATED);

  auto [status, bytes] = testing::health_check(make_farm_channel(coordinator_->address()));
  ASSERT_TRUE(status.ok()) << status.error_message();
  EXPECT_EQ(bytes, std::string("\x08\x01", 2));  // SERVING
}

TEST_F(FarmAuth, OwnerIsTheAuthenticatedCaller) {
  FarmClient alice = client(testing::kAliceToken);
  v1::JobSpec spec = testing::job_spec(*scene_, "sa", 4, 1);
  spec.set_owner("bob");  // a client's claim is replaced
  std::string job = alice.submit(spec).job_id();
  EXPECT_EQ(alice.status(job).owner(), "alice");
  FarmClient root = client(testing::kAdminToken);
  std::string admin_job = root.submit(testing::job_spec(*scene_, "sa", 4, 1)).job_id();
  EXPECT_EQ(root.status(admin_job).owner(), "root");
  alice.cancel(job);
  root.cancel(admin_job);
}

// Another client's job or batch is NOT_FOUND for status, watch, cancel, fetch and as a
// reference, with the very message of an id nobody holds (its existence does not leak); list
// shows the caller's own only; an admin sees and may cancel every job.
TEST_F(FarmAuth, AnotherClientsJobsAndBatchesAreNotFound) {
  FarmClient alice = client(testing::kAliceToken);
  FarmClient bob = client(testing::kBobToken);
  std::string job = alice.submit(testing::job_spec(*scene_, "sa", 4, 1)).job_id();
  std::string bobs = bob.submit(testing::job_spec(*scene_, "sa", 4, 2)).job_id();
  auto message_of = [](auto&& call) {
    try {
      call();
    } catch (const FarmCallError& error) {
      return std::to_string(int(error.code())) + " " + error.what();
    }
    return std::string("OK");
  };
  const std::string unknown = "job-999999";
  for (const std::string& id : {job, unknown}) {
    SCOPED_TRACE(id);
    EXPECT_EQ(code_of([&] { bob.status(id); }), StatusCode::NOT_FOUND);
    EXPECT_EQ(code_of([&] { bob.cancel(id); }), StatusCode::NOT_FOUND);
    EXPECT_EQ(code_of([&] { bob.fetch(id); }), StatusCode::NOT_FOUND);
    EXPECT_EQ(code_of([&] { bob.wait(id, 10s); }), StatusCode::NOT_FOUND);
    v1::JobSpec referencing = testing::job_spec(*scene_, "sa", 4, 3);
    referencing.set_reference_job(id);
    EXPECT_EQ(code_of([&] { bob.submit(referencing); }), StatusCode::NOT_FOUND);
  }
  // The same words as for an id nobody holds, but for the id itself.
  auto replace_id = [&](std::string text) {
    for (size_t at; (at = text.find(job)) != std::string::npos;) text.replace(at, job.size(), "ID");
    for (size_t at; (at = text.find(unknown)) != std::string::npos;)
      text.replace(at, unknown.size(), "ID");
    return text;
  };
  EXPECT_EQ(replace_id(message_of([&] { bob.status(job); })),
            replace_id(message_of([&] { bob.status(unknown); })));
  EXPECT_EQ(replace_id(message_of([&] { bob.cancel(job); })),
            replace_id(message_of([&] { bob.cancel(unknown); })));
  // Nothing happened to alice's job; each client lists its own jobs only.
  EXPECT_EQ(alice.status(job).state(), v1::JOB_STATE_QUEUED);
  for (const v1::JobStatus& listed : bob.list()) EXPECT_EQ(listed.owner(), "bob");
  for (const v1::JobStatus& listed : alice.list()) EXPECT_EQ(listed.owner(), "alice");
  auto lists = [](FarmClient& who, const std::string& id) {
    for (const v1::JobStatus& listed : who.list())
      if (listed.job_id() == id) return true;
    return false;
  };
  EXPECT_TRUE(lists(alice, job));
  EXPECT_FALSE(lists(bob, job));
  EXPECT_TRUE(lists(bob, bobs));
  // An admin sees both and may cancel either.
  FarmClient root = client(testing::kAdminToken);
  EXPECT_TRUE(lists(root, job));
  EXPECT_TRUE(lists(root, bobs));
  EXPECT_EQ(root.cancel(bobs), v1::JOB_STATE_CANCELLED);
  EXPECT_EQ(alice.cancel(job), v1::JOB_STATE_CANCELLED);

  // Batches: alice's batch is NOT_FOUND for bob (no worker runs here: it waits for its
  // reference).
  const std::string spec = R"({"format": "penumbra/batch@1", "name": "owned", "scene": ")" +
                           *scene_ + R"(", "methods": ["sa"], "budget": {"seconds": 1},
      "reference": {"method": "sa", "spp": 2}, "repeats": 1})";
  auto request = make_batch_request_from_text(spec, "owned.json", dir_->string(),
                                              [](const std::string& name) { return name; });
  BatchClient alice_batches(connection_to(coordinator_->address(), testing::kAliceToken));
  BatchClient bob_batches(connection_to(coordinator_->address(), testing::kBobToken));
  std::string batch = alice_batches.submit(request).batch_id();
  EXPECT_EQ(code_of([&] { bob_batches.status(batch); }), StatusCode::NOT_FOUND);
  EXPECT_EQ(code_of([&] { bob_batches.cancel(batch); }), StatusCode::NOT_FOUND);
  EXPECT_EQ(code_of([&] { bob_batches.fetch_reference(batch); }), StatusCode::NOT_FOUND);
  for (const v1::BatchStatus& listed : bob_batches.list()) EXPECT_NE(listed.batch_id(), batch);
  EXPECT_EQ(alice_batches.status(batch).owner(), "alice");
  EXPECT_EQ(alice_batches.cancel(batch).state(), v1::BATCH_STATE_CANCELLED);
}

TEST_F(FarmAuth, WorkerWithWorkerTokenRendersAndOneWithClientTokenIsRefused) {
  auto refused =
      testing::start_worker_with(coordinator_->address(), *dir_, "refused",
                                 {"--token", testing::kAliceToken, "--log-level", "warn"});
  EXPECT_EQ(refused->wait_exit(30s), 2);
  auto token_file = *dir_ / "worker.token";
  std::ofstream(token_file) << testing::kWorkerToken << "\n";
  auto worker = testing::start_worker_with(coordinator_->address(), *dir_, "w",
                                           {"--token-file", token_file.string()});
  FarmClient alice = client(testing::kAliceToken);
  std::string job = alice.submit(testing::job_spec(*scene_, "sa", 8, 5)).job_id();
  v1::JobStatus final_status = alice.wait(job, 60s);
  ASSERT_EQ(final_status.state(), v1::JOB_STATE_DONE) << final_status.error();
  testing::expect_bit_identical(alice, job, *scene_, "sa", 8, 5);
}

// --max-queued-jobs-per-client 2, no workers: a client's third unfinished job is refused with
// RESOURCE_EXHAUSTED naming the limit; another client is not affected; a cancelled job frees a
// place. --max-scene-mib 1: a larger package is refused in the request that carries it.
TEST(FarmLimits, QueuedJobsPerClientAndSceneSize) {
  auto dir = testing::fresh_directory("limits");
  std::string scene = testing::write_scene(dir, 32, 24);
  auto tokens = testing::write_tokens_file(dir);
  CoordinatorProcess coordinator(dir / "data", 0,
                                 {"--tokens-file", tokens.string(), "--max-queued-jobs-per-client",
                                  "2", "--max-scene-mib", "1"});
  FarmClient alice(connection_to(coordinator.address(), testing::kAliceToken));
  FarmClient bob(connection_to(coordinator.address(), testing::kBobToken));
  std::string first = alice.submit(testing::job_spec(scene, "sa", 4, 1)).job_id();
  alice.submit(testing::job_spec(scene, "sa", 4, 2));
  try {
    alice.submit(testing::job_spec(scene, "sa", 4, 3));
    ADD_FAILURE() << "a third unfinished job was accepted";
  } catch (const FarmCallError& error) {
    EXPECT_EQ(error.code(), StatusCode::RESOURCE_EXHAUSTED) << error.what();
    std::string message = error.what();
    EXPECT_NE(message.find("alice"), std::string::npos) << message;
    EXPECT_NE(message.find("--max-queued-jobs-per-client 2"), std::string::npos) << message;
  }
  EXPECT_EQ(alice.list().size(), 2u);
  EXPECT_EQ(code_of([&] { bob.submit(testing::job_spec(scene, "sa", 4, 4)); }), StatusCode::OK);
  alice.cancel(first);
  EXPECT_EQ(code_of([&] { alice.submit(testing::job_spec(scene, "sa", 4, 5)); }), StatusCode::OK);
  EXPECT_EQ(code_of([&] { alice.submit(testing::job_spec(scene, "sa", 4, 6)); }),
            StatusCode::RESOURCE_EXHAUSTED);

  // Scene size: 1.5 MiB of package files against a 1 MiB limit (the message stays under gRPC's
  // own limit, so the coordinator's check is what refuses it).
  v1::JobSpec big = testing::job_spec(scene, "sa", 4, 7);
  (*big.mutable_scene()->mutable_files())["padding.bin"] = std::string(3 << 19, 'x');
  try {
    bob.submit(big);
    ADD_FAILURE() << "an oversized scene was accepted";
  } catch (const FarmCallError& error) {
    EXPECT_EQ(error.code(), StatusCode::RESOURCE_EXHAUSTED) << error.what();
    EXPECT_NE(std::string(error.what()).find("limit of 1048576"), std::string::npos)
        << error.what();
  }
  // Still serving.
  EXPECT_EQ(code_of([&] { bob.list(); }), StatusCode::OK);
}

}  // namespace
}  // namespace penumbra::farm
#else
#include <gtest/gtest.h>
TEST(FarmNotBuilt, Skipped) {
  GTEST_SKIP() << "configured with PENUMBRA_FARM=OFF";
}
#endif
