// The client's farm commands against a real coordinator and worker: submit --wait, list, status,
// fetch, workers, and a readable error for an unknown job.
// Built only with the farm (PENUMBRA_FARM=ON); otherwise the program reports a skipped test.
#if __has_include("penumbra/v1/farm.pb.h")
#include <gtest/gtest.h>

#include "farm_test_support.h"

namespace penumbra::farm {
namespace {

using namespace std::chrono_literals;
using testing::ChildProcess;
using testing::CoordinatorProcess;

std::string read_text(const std::filesystem::path& path) {
  std::ifstream in(path);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

// Runs `penumbra ARGS...`; returns its exit code, its output in *output.
int run_client(const std::filesystem::path& dir, std::vector<std::string> arguments,
               std::string* output) {
  static int run = 0;
  auto log = dir / ("client-" + std::to_string(++run) + ".log");
  arguments.insert(arguments.begin(), testing::binary("client/penumbra"));
  ChildProcess client(arguments, log.string());
  int code = client.wait_exit(120s);
  *output = read_text(log);
  return code;
}

TEST(FarmClient, CommandsSubmitWatchListStatusFetchAndWorkers) {
  if (!std::filesystem::exists(testing::binary("client/penumbra")))
    GTEST_SKIP() << "build the penumbra client first";
  auto dir = testing::fresh_directory("client");
  std::string scene = testing::write_scene(dir, 64, 48);
  CoordinatorProcess coordinator(dir / "data");
  auto worker = testing::start_worker(coordinator.address(), dir, "w");
  const std::string at = "--coordinator=" + coordinator.address();
  std::string output;
  ASSERT_EQ(run_client(dir, {"submit", scene, "--spp", "8", "--seed", "3", "--wait", at}, &output),
            0)
      << output;
  EXPECT_NE(output.find("job-1 submitted"), std::string::npos) << output;
  EXPECT_NE(output.find("done"), std::string::npos) << output;
  ASSERT_EQ(run_client(dir, {"list", at}, &output), 0) << output;
  EXPECT_NE(output.find("farm-test"), std::string::npos) << output;
  ASSERT_EQ(run_client(dir, {"status", "job-1", at}, &output), 0) << output;
  EXPECT_NE(output.find("8 spp complete"), std::string::npos) << output;
  auto exr = dir / "job-1.exr";
  ASSERT_EQ(run_client(dir, {"fetch", "job-1", "-o", exr.string(), at}, &output), 0) << output;
  Image variance;
  Image color = read_exr(exr.string(), nullptr, &variance);
  Film local = testing::render_locally(scene, "sa", "stratified", 8, 3);
  EXPECT_TRUE(testing::same_bits(color, local.color));
  ASSERT_EQ(run_client(dir, {"workers", at}, &output), 0) << output;
  // Listed under its --name (the worker's id), not a generated one.
  EXPECT_NE(output.find("\nw" + std::string(23, ' ')), std::string::npos) << output;
  EXPECT_EQ(output.find("w1-w"), std::string::npos) << output;
  EXPECT_NE(run_client(dir, {"status", "job-9", at}, &output), 0);
  EXPECT_NE(output.find("NOT_FOUND"), std::string::npos) << output;
}

}  // namespace
}  // namespace penumbra::farm
#else
#include <gtest/gtest.h>
TEST(FarmNotBuilt, Skipped) {
  GTEST_SKIP() << "configured with PENUMBRA_FARM=OFF";
}
#endif
