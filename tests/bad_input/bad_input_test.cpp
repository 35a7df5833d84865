// The bad-input corpus (tests/data/bad_input/) against a live coordinator and worker (real
// processes, as tests/farm): each case gets its exact gRPC status and a message naming what is
// wrong (methods that parse but cannot run on the scene included: the coordinator builds the
// estimator at submission); afterwards both processes are still up and a good job completes.
// Built only with the farm.
#if __has_include("penumbra/v1/farm.pb.h")
#include <google/protobuf/descriptor.h>
#include <google/protobuf/message.h>
#include <google/protobuf/text_format.h>
#include <grpcpp/generic/generic_stub.h>
#include <gtest/gtest.h>

#include <condition_variable>
#include <iostream>
#include <mutex>

#include "../farm/farm_test_support.h"
#include "bad_input_cases.h"
#include "core/render/tile.h"
#include "penumbra/version.h"

namespace penumbra::bad_input {
namespace {

using namespace std::chrono_literals;
namespace testing = farm::testing;

struct CallResult {
  grpc::Status status;
  std::string response;
};

// One unary call with the request as bytes, so that any bytes (not only valid messages) can be
// sent to any method.
CallResult call(grpc::GenericStub& stub, const std::string& method, const std::string& request) {
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + 60s);
  grpc::Slice slice(request);
  grpc::ByteBuffer request_bytes(&slice, 1);
  grpc::ByteBuffer response_bytes;
  std::mutex mutex;
  std::condition_variable done;
  bool finished = false;
  CallResult result;
  stub.UnaryCall(&context, method, grpc::StubOptions(), &request_bytes, &response_bytes,
                 [&](grpc::Status status) {
                   std::lock_guard lock(mutex);
                   result.status = status;
                   finished = true;
                   done.notify_all();
                 });
  std::unique_lock lock(mutex);
  done.wait(lock, [&] { return finished; });
  std::vector<grpc::Slice> slices;
  if (result.status.ok() && response_bytes.Dump(&slices).ok())
    for (const auto& s : slices)
      result.response.append(reinterpret_cast<const char*>(s.begin()), s.size());
  return result;
}

// "/penumbra.v1.Jobs/SubmitJob" -> a fresh request message of that method.
std::unique_ptr<google::protobuf::Message> request_message(const std::string& rpc) {
  std::string full_name = rpc.substr(1);
  std::replace(full_name.begin(), full_name.end(), '/', '.');
  const auto* method =
      google::protobuf::DescriptorPool::generated_pool()->FindMethodByName(full_name);
  if (!method) throw std::runtime_error("no method " + rpc);
  return std::unique_ptr<google::protobuf::Message>(
      google::protobuf::MessageFactory::generated_factory()
          ->GetPrototype(method->input_type())
          ->New());
}

class BadInputFarm : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = testing::fresh_directory("bad-input-corpus");
    // Small limits so the oversized cases stay small: packages up to 1 MiB, messages 17 MiB.
    coordinator_ = std::make_unique<testing::CoordinatorProcess>(
        dir_ / "data", 0, std::vector<std::string>{"--max-scene-mib", "1"}, 2.0);
    worker_ = testing::start_worker(coordinator_->address(), dir_, "worker");
    stub_ = std::make_unique<grpc::GenericStub>(farm::make_farm_channel(coordinator_->address()));
    client_ = std::make_unique<farm::FarmClient>(coordinator_->address());
    good_scene_ = farm::pack_scene_file((corpus_root() / "good" / "base.json").string());
  }
  void TearDown() override {
    client_.reset();
    stub_.reset();
    worker_.reset();
    coordinator_.reset();
    if (!HasFailure()) std::filesystem::remove_all(dir_);
  }

  // Sends a case's request and checks its status and message; returns the call's result.
  CallResult expect_refusal(const BadInputCase& c, const std::string& rpc,
                            const std::string& request) {
    CallResult result = call(*stub_, rpc, request);
    std::string status = c.status(), message = c.message();
    if (auto known = c.get("known_bug_status")) {
      // A bug in a file this test does not own, described in the .expect: the case checks that
      // it is still there, so the .expect gets updated once it is fixed.
      std::cout << c.name << ": known bug, see its .expect\n";
      status = *known;
      message = c.get("known_bug_message").value_or("");
    }
    EXPECT_EQ(farm::status_code_name(result.status.error_code()), status)
        << c.name << ": " << result.status.error_message();
    EXPECT_NE(result.status.error_message().find(message), std::string::npos)
        << c.name << ": the message does not name the problem: " << result.status.error_message();
    EXPECT_TRUE(coordinator_->process().running()) << c.name << ": the coordinator died";
    return result;
  }

  v1::SubmitJobRequest submission(const std::string& method) {
    v1::SubmitJobRequest request;
    *request.mutable_spec()->mutable_scene() = good_scene_;
    request.mutable_spec()->set_method(method);
    request.mutable_spec()->set_spp(4);
    return request;
  }

  std::filesystem::path dir_;
  std::unique_ptr<testing::CoordinatorProcess> coordinator_;
  std::unique_ptr<testing::ChildProcess> worker_;
  std::unique_ptr<grpc::GenericStub> stub_;
  std::unique_ptr<farm::FarmClient> client_;
  v1::ScenePackage good_scene_;
};

TEST_F(BadInputFarm, EveryCaseGetsItsStatusAndBothProcessesKeepServing) {
  const std::string submit = "/penumbra.v1.Jobs/SubmitJob";

  // Scenes, as uploaded packages.
  for (const BadInputCase& c : load_cases("scenes")) {
    if (c.get("wire") == "none") continue;
    v1::SubmitJobRequest request = submission("sa");
    v1::ScenePackage* package = request.mutable_spec()->mutable_scene();
    package->Clear();
    package->set_scene_json(c.text());
    package->set_source_name(c.path.filename().string());
    for (const auto& [path, bytes] : c.package_files()) (*package->mutable_files())[path] = bytes;
    expect_refusal(c, submit, request.SerializeAsString());
  }

  // Methods, with the good scene.
  for (const BadInputCase& c : load_cases("methods"))
    expect_refusal(c, submit, submission(c.text()).SerializeAsString());

  // Requests of every service.
  for (const BadInputCase& c : load_cases("requests")) {
    std::string rpc = c.get("rpc").value_or(submit);
    std::string bytes = c.text();
    if (c.get("raw") != "yes") {
      auto message = request_message(rpc);
      ASSERT_TRUE(google::protobuf::TextFormat::ParseFromString(bytes, message.get())) << c.name;
      const auto* descriptor = message->GetDescriptor();
      const auto* reflection = message->GetReflection();
      if (c.get("fill") == "tile")
        reflection->SetString(message.get(), descriptor->FindFieldByName("tile"),
                              TileAccumulator(TileRect{0, 0, 1, 1}).serialize());
      if (c.get("fill") == "build_flavour")
        reflection->SetString(message.get(), descriptor->FindFieldByName("build_flavour"),
                              kBuildFlavour);
      if (auto* request = dynamic_cast<v1::SubmitJobRequest*>(message.get())) {
        if (c.get("scene") == "good") *request->mutable_spec()->mutable_scene() = good_scene_;
        if (auto mib = c.get("pad_mib"))
          (*request->mutable_spec()->mutable_scene()->mutable_files())["padding.bin"] =
              std::string(size_t(std::stoi(*mib)) << 20, '#');
      }
      bytes = message->SerializeAsString();
    }
    expect_refusal(c, rpc, bytes);
  }

  // Still serving: both processes are up and a good job completes.
  ASSERT_TRUE(coordinator_->process().running());
  ASSERT_TRUE(worker_->running()) << "the worker died; see " << (dir_ / "worker.log");
  auto good = client_->submit(submission("bsdf+sa").spec());
  v1::JobStatus status = testing::wait_until(
      *client_, good.job_id(),
      [](const v1::JobStatus& s) {
        return s.state() == v1::JOB_STATE_DONE || s.state() == v1::JOB_STATE_FAILED;
      },
      60s);
  EXPECT_EQ(status.state(), v1::JOB_STATE_DONE) << status.error();
  EXPECT_FALSE(client_->fetch(good.job_id()).empty());
  EXPECT_TRUE(worker_->running());
}

}  // namespace
}  // namespace penumbra::bad_input
#else
#include <gtest/gtest.h>
TEST(BadInputFarmNotBuilt, Skipped) {
  GTEST_SKIP() << "configured with PENUMBRA_FARM=OFF";
}
#endif
