// Ctrl-C during `penumbra render`: the first SIGINT stops the render at a pass boundary and
// writes the partial image, which states its spp and is bit-identical to a render of exactly that
// many passes (whole passes: unbiased), and its exact sums, which merge with the passes after
// them (`render --first-pass`, `penumbra merge`) into the bits of one uninterrupted render; a
// second SIGINT aborts without writing. Output that is not a terminal gets plain progress lines.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <thread>

#include "core/image/image.h"
#include "core/render/local_render.h"
#include "core/scene/scene.h"

extern char** environ;

namespace penumbra {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

// A floor under a quad light with a small occluder; 32x24 pixels, so a pass takes well under a
// millisecond and a million passes far longer than the test.
const char* kScene = R"({
  "format": "penumbra/scene@1", "name": "interrupt-test",
  "camera": { "position": [0, 1.2, 2.5], "look_at": [0, 0.3, 0], "up": [0, 1, 0],
              "fov_y_deg": 50, "width": 32, "height": 24 },
  "materials": { "white": { "type": "lambert", "albedo": [0.8, 0.8, 0.8] } },
  "shapes": [
    { "type": "quad", "origin": [-1, 0, -1], "edge1": [2, 0, 0], "edge2": [0, 0, 2], "material": "white" },
    { "type": "box", "min": [-0.2, 0.4, -0.2], "max": [0.2, 0.45, 0.2], "material": "white" }
  ],
  "lights": [ { "type": "quad", "origin": [-0.25, 1, -0.25], "edge1": [0.5, 0, 0], "edge2": [0, 0, 0.5],
                "radiance": [5, 5, 5] } ]
})";

const fs::path kPenumbra = fs::path(PENUMBRA_BINARY_DIR) / "client" / "penumbra";

std::string read_text(const fs::path& path) {
  std::ifstream file(path, std::ios::binary);
  std::stringstream text;
  text << file.rdbuf();
  return text.str();
}

struct Child {
  pid_t pid = 0;
  fs::path out, err;
};

// `penumbra render` with its standard output and error in files (not a terminal).
Child start_render(const fs::path& dir, const fs::path& scene, const fs::path& exr) {
  Child child;
  child.out = dir / "stdout.txt";
  child.err = dir / "stderr.txt";
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&actions, 1, child.out.c_str(), O_WRONLY | O_CREAT | O_TRUNC,
                                   0644);
  posix_spawn_file_actions_addopen(&actions, 2, child.err.c_str(), O_WRONLY | O_CREAT | O_TRUNC,
                                   0644);
  std::vector<std::string> args = {kPenumbra.string(),
                                   "render",
                                   scene.string(),
                                   "--method",
                                   "sa",
                                   "--sampler",
                                   "stratified",
                                   "--seed",
                                   "7",
                                   "--spp",
                                   "1000000",
                                   "--threads",
                                   "1",
                                   "-o",
                                   exr.string()};
  std::vector<char*> argv;
  for (std::string& arg : args) argv.push_back(arg.data());
  argv.push_back(nullptr);
  EXPECT_EQ(posix_spawn(&child.pid, kPenumbra.c_str(), &actions, nullptr, argv.data(), environ), 0);
  posix_spawn_file_actions_destroy(&actions);
  return child;
}

// Waits until `file` contains `text`; false after 15 s.
bool wait_for(const fs::path& file, const std::string& text) {
  const auto deadline = Clock::now() + std::chrono::seconds(15);
  while (Clock::now() < deadline) {
    if (read_text(file).find(text) != std::string::npos) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return false;
}

int wait_exit(pid_t pid);

// Runs `penumbra ARGS...` to its end with its output in `log`; returns its exit status.
int run_penumbra(const fs::path& log, std::vector<std::string> args) {
  args.insert(args.begin(), kPenumbra.string());
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&actions, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&actions, 1, 2);
  std::vector<char*> argv;
  for (std::string& arg : args) argv.push_back(arg.data());
  argv.push_back(nullptr);
  pid_t pid = 0;
  EXPECT_EQ(posix_spawn(&pid, kPenumbra.c_str(), &actions, nullptr, argv.data(), environ), 0);
  posix_spawn_file_actions_destroy(&actions);
  return wait_exit(pid);
}

int wait_exit(pid_t pid) {
  int status = 0;
  const auto deadline = Clock::now() + std::chrono::seconds(15);
  while (Clock::now() < deadline) {
    if (waitpid(pid, &status, WNOHANG) == pid) return status;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  kill(pid, SIGKILL);
  waitpid(pid, &status, 0);
  ADD_FAILURE() << "penumbra render did not end within 15 s of Ctrl-C";
  return status;
}

class RenderInterrupt : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!fs::exists(kPenumbra))
      GTEST_SKIP() << "no " << kPenumbra << " (build the penumbra target)";
    const auto* test = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::path(PENUMBRA_BINARY_DIR) / "test-output" / "client" / test->name();
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    scene_ = dir_ / "scene.json";
    std::ofstream(scene_) << kScene;
  }
  fs::path dir_, scene_;
};

TEST_F(RenderInterrupt, FirstCtrlCWritesTheWholePassesDone) {
  const fs::path exr = dir_ / "partial.exr";
  Child child = start_render(dir_, scene_, exr);
  // Plain progress: the first line comes after the first pass.
  ASSERT_TRUE(wait_for(child.err, "render interrupt-test: ")) << read_text(child.err);
  kill(child.pid, SIGINT);
  int status = wait_exit(child.pid);
  ASSERT_TRUE(WIFEXITED(status)) << "ended by signal " << WTERMSIG(status);
  EXPECT_EQ(WEXITSTATUS(status), 130);

  const std::string out = read_text(child.out), err = read_text(child.err);
  std::smatch match;
  ASSERT_TRUE(std::regex_search(out, match,
                                std::regex("render interrupted: the partial image has (\\d+) spp")))
      << out;
  const uint32_t spp = uint32_t(std::stoul(match[1]));
  EXPECT_GE(spp, 1u);
  EXPECT_LT(spp, 1000000u);
  EXPECT_NE(err.find("stopping at the next pass boundary"), std::string::npos) << err;
  // Not a terminal: whole lines, no carriage return or escape sequence.
  EXPECT_EQ(err.find('\r'), std::string::npos);
  EXPECT_EQ(err.find('\033'), std::string::npos);
  EXPECT_TRUE(std::regex_search(
      err,
      std::regex("render interrupt-test: \\d+/1000000 spp \\(\\d+%\\), [0-9.e+]+ spp/s, ETA ")))
      << err;

  ImageMetadata metadata;
  Image image = read_exr(exr.string(), &metadata);
  EXPECT_EQ(metadata["penumbra:spp"], std::to_string(spp));
  EXPECT_EQ(metadata["penumbra:interrupted"],
            "after " + std::to_string(spp) + " whole passes of 1000000");

  // The same passes rendered here, uninterrupted: the same bits.
  auto scene = std::make_shared<const Scene>(load_scene(scene_.string()));
  Renderer renderer(scene, RenderOptions{"sa", Pattern::Stratified, 7});
  RenderBudget budget;
  budget.spp = spp;
  LocalRenderResult expected = render_local(renderer, budget, 2);
  ASSERT_EQ(image.rgb.size(), expected.film.color.rgb.size());
  size_t different = 0;
  for (size_t i = 0; i < image.rgb.size(); ++i)
    different += image.rgb[i] != expected.film.color.rgb[i];
  EXPECT_EQ(different, 0u) << "of " << image.rgb.size() << " channels";
}

TEST_F(RenderInterrupt, PartialImageMergesWithTheRemainingPassesBitForBit) {
  const fs::path exr = dir_ / "partial.exr";
  Child child = start_render(dir_, scene_, exr);
  ASSERT_TRUE(wait_for(child.err, "render interrupt-test: ")) << read_text(child.err);
  kill(child.pid, SIGINT);
  int status = wait_exit(child.pid);
  ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 130) << read_text(child.err);
  const std::string out = read_text(child.out);
  std::smatch match;
  ASSERT_TRUE(std::regex_search(out, match, std::regex("partial image has (\\d+) spp"))) << out;
  const uint32_t spp = uint32_t(std::stoul(match[1]));
  // The sums are beside the EXR, and the message says how to go on.
  const fs::path sums = dir_ / "partial.sums";
  ASSERT_TRUE(fs::exists(sums));
  EXPECT_NE(out.find("its exact sums are in " + sums.string() +
                     ": render the remaining passes "
                     "with --first-pass " +
                     std::to_string(spp) + " --spp " + std::to_string(1000000 - spp)),
            std::string::npos)
      << out;

  // The next 16 passes, later, with another tile size; then the merge (the EXR's sums found
  // beside it).
  const uint32_t more = 16;
  ASSERT_EQ(run_penumbra(dir_ / "rest.log", {"render",       scene_.string(),
                                             "--method",     "sa",
                                             "--sampler",    "stratified",
                                             "--seed",       "7",
                                             "--first-pass", std::to_string(spp),
                                             "--spp",        std::to_string(more),
                                             "--tile",       "8",
                                             "--reference",  exr.string(),
                                             "--sums",       (dir_ / "rest.sums").string(),
                                             "-o",           (dir_ / "rest.exr").string()}),
            0)
      << read_text(dir_ / "rest.log");
  // With a reference, the progress lines carry the MRSE of the image so far.
  EXPECT_TRUE(std::regex_search(read_text(dir_ / "rest.log"),
                                std::regex("render interrupt-test: 16/16 spp \\(100%\\), .*, "
                                           "MRSE [0-9.e+-]+\n")))
      << read_text(dir_ / "rest.log");
  const fs::path merged = dir_ / "merged.exr";
  ASSERT_EQ(run_penumbra(dir_ / "merge.log", {"merge", exr.string(), (dir_ / "rest.sums").string(),
                                              "-o", merged.string()}),
            0)
      << read_text(dir_ / "merge.log");
  EXPECT_NE(read_text(dir_ / "merge.log")
                .find("merged 2 part(s): passes 0.." + std::to_string(spp + more)),
            std::string::npos)
      << read_text(dir_ / "merge.log");

  // One uninterrupted render of all those passes: the same bits, colour and variance.
  ImageMetadata metadata;
  Image variance;
  Image image = read_exr(merged.string(), &metadata, &variance);
  EXPECT_EQ(metadata["penumbra:spp"], std::to_string(spp + more));
  EXPECT_EQ(metadata.count("penumbra:interrupted"), 0u);
  auto scene = std::make_shared<const Scene>(load_scene(scene_.string()));
  Renderer renderer(scene, RenderOptions{"sa", Pattern::Stratified, 7});
  RenderBudget budget;
  budget.spp = spp + more;
  LocalRenderResult expected = render_local(renderer, budget, 2);
  EXPECT_EQ(image.rgb, expected.film.color.rgb);
  EXPECT_EQ(variance.rgb, expected.film.variance.rgb);

  // A merge that would count passes twice is refused, naming the files.
  EXPECT_NE(run_penumbra(dir_ / "twice.log", {"merge", sums.string(), sums.string(), "-o",
                                              (dir_ / "twice.exr").string()}),
            0);
  EXPECT_NE(read_text(dir_ / "twice.log").find("a pass would count twice"), std::string::npos)
      << read_text(dir_ / "twice.log");
}

TEST_F(RenderInterrupt, SecondCtrlCAborts) {
  // The second SIGINT must arrive while the render is still finishing its pass block (about
  // half a second); when the block ends first the partial image is written instead, and the
  // attempt is repeated.
  for (int attempt = 0; attempt < 3; ++attempt) {
    const fs::path exr = dir_ / ("aborted" + std::to_string(attempt) + ".exr");
    Child child = start_render(dir_, scene_, exr);
    ASSERT_TRUE(wait_for(child.err, "render interrupt-test: ")) << read_text(child.err);
    kill(child.pid, SIGINT);
    ASSERT_TRUE(wait_for(child.err, "Ctrl-C again to abort")) << read_text(child.err);
    kill(child.pid, SIGINT);
    int status = wait_exit(child.pid);
    if (WIFEXITED(status) && read_text(child.out).find("render interrupted") != std::string::npos)
      continue;  // the block ended before the second signal
    EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGINT)
        << "exit status " << status << "; stderr: " << read_text(child.err);
    EXPECT_FALSE(fs::exists(exr));
    EXPECT_NE(read_text(child.err).find("penumbra: aborted"), std::string::npos);
    return;
  }
  FAIL() << "three times the render wrote its partial image before the second Ctrl-C";
}

}  // namespace
}  // namespace penumbra
