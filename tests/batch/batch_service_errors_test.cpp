// The Batches service's errors: a bad spec is INVALID_ARGUMENT naming its field (JSON path), an
// unknown batch or reference job NOT_FOUND, on every method of the service.
#if __has_include("penumbra/v1/farm.pb.h")
#include <gtest/gtest.h>

#include <fstream>

#include "core/image/image.h"
#include "server/embedded_farm.h"
#include "tests/batch/batch_test_support.h"
#include "tests/farm/farm_test_support.h"

namespace penumbra::farm {
namespace {

std::string spec(const std::string& methods, const std::string& budget,
                 const std::string& extra = "") {
  return R"({"format": "penumbra/batch@1", "scene": "batch-test.json", "methods": )" + methods +
         R"(, "budget": )" + budget + extra + "}";
}

void expect_status(const std::function<void()>& call, grpc::StatusCode code,
                   const std::string& words) {
  try {
    call();
    ADD_FAILURE() << "no error; wanted " << status_code_name(code) << " with '" << words << "'";
  } catch (const FarmCallError& error) {
    EXPECT_EQ(error.code(), code) << error.what();
    EXPECT_NE(std::string(error.what()).find(words), std::string::npos)
        << "wanted '" << words << "': " << error.what();
  }
}

class BatchServiceErrors : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = testing::fresh_directory("batch-errors");
    testing::write_batch_scene(dir_, 16);
    farm_ = std::make_unique<EmbeddedFarm>(EmbeddedFarmOptions{1, 1, "", {}});
    client_ = std::make_unique<BatchClient>(farm_->address());
  }
  void TearDown() override {
    client_.reset();
    farm_.reset();
    std::filesystem::remove_all(dir_);
  }
  v1::SubmitBatchRequest request(const std::string& json) {
    v1::SubmitBatchRequest r;
    r.set_spec_json(json);
    r.set_source_name("bad.json");
    *r.mutable_scene() = pack_scene_file((dir_ / "batch-test.json").string());
    return r;
  }
  void expect_submit(const std::string& json, grpc::StatusCode code, const std::string& words) {
    expect_status([&] { client_->submit(request(json)); }, code, words);
  }

  std::filesystem::path dir_;
  std::unique_ptr<EmbeddedFarm> farm_;
  std::unique_ptr<BatchClient> client_;
};

TEST_F(BatchServiceErrors, BadSpecsNameTheirField) {
  using grpc::StatusCode;
  expect_submit("{", StatusCode::INVALID_ARGUMENT, "invalid JSON");
  expect_submit(spec(R"(["sa"])", R"({"seconds": -1})"), StatusCode::INVALID_ARGUMENT,
                "$.budget.seconds");
  expect_submit(spec(R"(["sa"])", R"({"seconds": 0})"), StatusCode::INVALID_ARGUMENT,
                "$.budget.seconds");
  expect_submit(spec(R"(["sa", "what"])", R"({"spp": [2]})"), StatusCode::INVALID_ARGUMENT,
                "$.methods[1]");
  expect_submit(spec(R"(["sa"])", R"({"spp": [2]})", R"(, "regions": {"big": [0, 0, 17, 4]})"),
                StatusCode::INVALID_ARGUMENT, "$.regions.big");
  expect_submit(spec(R"(["sa"])", R"({"spp": [2]})", R"(, "reference": "missing.exr")"),
                StatusCode::INVALID_ARGUMENT, "$.reference");
  expect_submit(spec(R"(["sa"])", R"({"spp": [2]})", R"(, "reference": "job:job-999")"),
                StatusCode::NOT_FOUND, "$.reference");
  expect_submit(spec(R"(["sa"])", R"({"spp": [2]})", R"(, "reference": "job:nonsense")"),
                StatusCode::NOT_FOUND, "$.reference");

  // A reference EXR of another size.
  v1::SubmitBatchRequest wrong_size =
      request(spec(R"(["sa"])", R"({"spp": [2]})", R"(, "reference": "ref.exr")"));
  Image small(8, 8);
  wrong_size.set_reference_exr(encode_exr(small, nullptr, {}));
  expect_status([&] { client_->submit(wrong_size); }, grpc::StatusCode::INVALID_ARGUMENT,
                "$.reference");

  // A scene whose reader warns (a misspelled key): refused under "strict": true, naming the key.
  {
    std::ifstream in(dir_ / "batch-test.json");
    std::string json((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    json.replace(json.find("\"fov_y_deg\": 40"), 15, "\"fov_y_deg\": 40, \"fovy\": 30");
    std::ofstream(dir_ / "typo.json") << json;
  }
  v1::SubmitBatchRequest strict =
      request(spec(R"(["sa"])", R"({"spp": [2]})", R"(, "strict": true)"));
  *strict.mutable_scene() = pack_scene_file((dir_ / "typo.json").string());
  expect_status([&] { client_->submit(strict); }, grpc::StatusCode::INVALID_ARGUMENT,
                "$.strict: the scene has 1 warning(s)");
  expect_status([&] { client_->submit(strict); }, grpc::StatusCode::INVALID_ARGUMENT,
                "$.camera.fovy");

  // No scene package.
  v1::SubmitBatchRequest no_scene = request(spec(R"(["sa"])", R"({"spp": [2]})"));
  no_scene.clear_scene();
  expect_status([&] { client_->submit(no_scene); }, grpc::StatusCode::INVALID_ARGUMENT, "scene");
  EXPECT_TRUE(client_->list().empty());
}

TEST_F(BatchServiceErrors, UnknownBatchesAreNotFound) {
  using grpc::StatusCode;
  for (std::string id : {"batch-999", "nonsense", "", "batch-"}) {
    expect_status([&] { client_->status(id); }, StatusCode::NOT_FOUND, "no batch");
    expect_status([&] { client_->cancel(id); }, StatusCode::NOT_FOUND, "no batch");
    expect_status([&] { client_->fetch_reference(id); }, StatusCode::NOT_FOUND, "no batch");
    expect_status([&] { client_->watch(id, {}, std::chrono::seconds(10)); }, StatusCode::NOT_FOUND,
                  "no batch");
  }
}

TEST_F(BatchServiceErrors, CancelStopsABatch) {
  auto response = client_->submit(
      request(spec(R"(["sa"])", R"({"spp": [100000]})", R"(, "reference": {"spp": 100000})")));
  v1::BatchStatus cancelled = client_->cancel(response.batch_id());
  EXPECT_EQ(cancelled.state(), v1::BATCH_STATE_CANCELLED);
  v1::BatchStatus watched = client_->watch(response.batch_id(), {}, std::chrono::seconds(10));
  EXPECT_EQ(watched.state(), v1::BATCH_STATE_CANCELLED);
  EXPECT_THROW(write_batch_result(*client_, watched, dir_ / "out"), std::runtime_error);
}

}  // namespace
}  // namespace penumbra::farm
#else
#include <gtest/gtest.h>
TEST(FarmNotBuilt, Skipped) {
  GTEST_SKIP() << "configured with PENUMBRA_FARM=OFF";
}
#endif
