// What `penumbra render` (and the other commands that load a scene) refuse before any work: an
// output that is not an EXR (-o out.png would have lost the image), a folder that does not
// exist, a reference that is missing, of another resolution or of another scene (unless
// --accept-reference-mismatch, which warns and records it), a seed out of range, and with
// --strict a scene whose reader warns. Misspelled keys warn and travel in the EXR's metadata.
// The checks run in this process (client/scene_checks.cpp is compiled in); a few runs of the
// built client on a 16x12 scene check the commands end to end.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "client/cli_options.h"
#include "client/scene_checks.h"
#include "core/image/image.h"
#include "core/scene/scene.h"

namespace penumbra {
namespace {

namespace fs = std::filesystem;

std::string client_binary() {
  return std::string(PENUMBRA_BINARY_DIR) + "/client/penumbra";
}

std::string read_text(const fs::path& path) {
  std::ifstream in(path);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

struct CliRun {
  int code = -1;
  std::string output;  // stdout and stderr
};

CliRun run(const fs::path& dir, const std::vector<std::string>& arguments) {
  static int count = 0;
  const fs::path log = dir / ("run-" + std::to_string(++count) + ".log");
  std::string command = "'" + client_binary() + "'";
  for (const std::string& argument : arguments) command += " '" + argument + "'";
  command += " > '" + log.string() + "' 2>&1";
  const int status = std::system(command.c_str());
  CliRun result;
  result.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  result.output = read_text(log);
  return result;
}

// A small scene; `extra_camera` and `extra_light` are spliced into those objects (typos), and
// `radiance` makes another scene of the same resolution.
std::string scene_json(int width, int height, const std::string& extra_camera = "",
                       const std::string& extra_light = "", const std::string& extra_material = "",
                       const std::string& extra_shape = "", double radiance = 5) {
  std::ostringstream json;
  json << R"({"format": "penumbra/scene@1", "name": "cli-test",
  "camera": {"position": [0, 1.2, 3.0], "look_at": [0, 0.3, 0], "up": [0, 1, 0],
             "fov_y_deg": 40, "width": )"
       << width << ", \"height\": " << height << extra_camera << R"(},
  "materials": {"white": {"type": "lambert", "albedo": [0.8, 0.8, 0.8])"
       << extra_material << R"(}},
  "shapes": [{"type": "quad", "origin": [-2, 0, 2], "edge1": [4, 0, 0], "edge2": [0, 0, -4],
              "material": "white")"
       << extra_shape << R"(}],
  "lights": [{"type": "quad", "origin": [-0.5, 1.5, -0.5], "edge1": [1, 0, 0],
              "edge2": [0, 0, 1], "radiance": [)"
       << radiance << ", " << radiance << ", " << radiance << "]" << extra_light << "}]}";
  return json.str();
}

class CliChecks : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!fs::exists(client_binary())) GTEST_SKIP() << "build the penumbra client first";
    dir_ = fs::temp_directory_path() /
           ("penumbra-cli-checks-" + std::to_string(::getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    scene_ = write("scene.json", scene_json(16, 12));
  }
  void TearDown() override {
    if (!dir_.empty()) fs::remove_all(dir_);
  }
  std::string write(const std::string& name, const std::string& text) {
    std::ofstream(dir_ / name) << text;
    return (dir_ / name).string();
  }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }

  fs::path dir_;
  std::string scene_;
};

// The checks themselves, in this process (client/scene_checks.h, client/cli_options.h).
TEST_F(CliChecks, OutputsReferencesAndSeedsAreCheckedBeforeAnyWork) {
  EXPECT_NO_THROW(check_output_path(path("a.exr"), {".exr"}, "-o"));
  auto refusal = [](auto&& call) {
    try {
      call();
    } catch (const std::exception& error) {
      return std::string(error.what());
    }
    return std::string("accepted");
  };
  EXPECT_NE(refusal([&] {
              check_output_path(path("a.png"), {".exr"}, "-o");
            }).find("must end in .exr, not .png"),
            std::string::npos);
  EXPECT_NE(refusal([&] {
              check_output_path(path("missing/a.exr"), {".exr"}, "-o");
            }).find("does not exist"),
            std::string::npos);
  fs::create_directories(path("folder.exr"));
  EXPECT_NE(refusal([&] {
              check_output_path(path("folder.exr"), {".exr"}, "-o");
            }).find("is a directory"),
            std::string::npos);

  // References: written with and without a scene hash, in two resolutions.
  const Scene scene = load_scene(scene_);
  Image image(16, 12), small(8, 6);
  write_exr(path("same.exr"), image, nullptr, {{"scene_hash", scene.content_hash}});
  write_exr(path("other.exr"), image, nullptr,
            {{"scene_hash", std::string(64, 'a')}, {"scene", "elsewhere"}});
  write_exr(path("foreign.exr"), image, nullptr, {});
  write_exr(path("small.exr"), small, nullptr, {{"scene_hash", scene.content_hash}});
  EXPECT_TRUE(check_reference(path("same.exr"), scene, false).warnings.empty());
  EXPECT_TRUE(check_reference(path("foreign.exr"), scene, false).warnings.empty())
      << "an EXR without a scene hash cannot be checked";
  const std::string other = refusal([&] { check_reference(path("other.exr"), scene, false); });
  EXPECT_NE(other.find("another scene (elsewhere)"), std::string::npos) << other;
  EXPECT_NE(other.find("--accept-reference-mismatch"), std::string::npos);
  std::vector<std::string> accepted = check_reference(path("other.exr"), scene, true).warnings;
  ASSERT_EQ(accepted.size(), 1u);
  EXPECT_NE(accepted[0].find("accepted by --accept-reference-mismatch"), std::string::npos);
  EXPECT_NE(refusal([&] { check_reference(path("small.exr"), scene, true); }).find("8x6"),
            std::string::npos);
  EXPECT_NE(
      refusal([&] { check_reference(path("nothing.exr"), scene, false); }).find("no such file"),
      std::string::npos);

  // Seeds: decimal, in [0, 2^64 - 1].
  CLI::Validator seed = seed_check();
  for (std::string text : {"0", "7", "18446744073709551615"}) EXPECT_EQ(seed(text), "") << text;
  for (std::string text : {"-1", "18446744073709551616", "12x", "", "1e3"})
    EXPECT_NE(seed(text).find("the seed is an integer in [0, 18446744073709551615]"),
              std::string::npos)
        << text;
}

TEST_F(CliChecks, SceneWarningsArePrintedOrRefusedByStrict) {
  const std::string typos =
      write("typos.json", scene_json(16, 12, R"(, "fovy": 30)",
                                     R"(, "profle": {"type": "gaussian", "sigma": 0.2})",
                                     R"(, "colour": [1, 0, 0])", R"(, "materialz": "white")"));
  const std::vector<std::string> keys = {"$.camera.fovy", "$.lights[0].profle",
                                         "$.materials.white.colour", "$.shapes[0].materialz"};
  const Scene scene = load_scene(typos);
  try {
    report_scene_warnings(scene, true, typos);
    ADD_FAILURE() << "--strict let the warnings pass";
  } catch (const FormatError& error) {
    for (const std::string& key : keys)
      EXPECT_NE(std::string(error.what()).find(key), std::string::npos) << key;
    EXPECT_NE(std::string(error.what()).find("--strict"), std::string::npos);
  }
  EXPECT_NO_THROW(report_scene_warnings(load_scene(scene_), true, scene_));
}

// The commands end to end (each run of the client costs about a second: few of them).
TEST_F(CliChecks, RenderRefusesAPngOutputAndCarriesTheScenesWarnings) {
  const std::string typos = write(
      "typos.json",
      scene_json(16, 12, R"(, "fovy": 30)", R"(, "profle": {"type": "gaussian", "sigma": 0.2})"));
  CliRun png = run(dir_, {"render", typos, "--spp", "1", "-o", path("out.png")});
  EXPECT_NE(png.code, 0) << png.output;
  EXPECT_NE(png.output.find("out.exr to get both"), std::string::npos) << png.output;
  EXPECT_FALSE(fs::exists(path("out.png")));
  CliRun strict = run(dir_, {"probe", typos, write("probe.json", R"({"format": "penumbra/probe@1",
      "pixels": [[8, 6]]})"),
                             "--strict"});
  EXPECT_NE(strict.code, 0);
  EXPECT_NE(strict.output.find("$.lights[0].profle"), std::string::npos) << strict.output;
  CliRun exr = run(dir_, {"render", typos, "--spp", "1", "-o", path("out.exr"), "--seed",
                          "18446744073709551615"});
  ASSERT_EQ(exr.code, 0) << exr.output;
  EXPECT_NE(exr.output.find("warning: $.camera.fovy"), std::string::npos) << exr.output;
  EXPECT_NE(exr.output.find("warning: $.lights[0].profle"), std::string::npos);
  ImageMetadata metadata;
  read_exr(path("out.exr"), &metadata);
  EXPECT_NE(metadata["penumbra:warnings"].find("$.lights[0].profle"), std::string::npos);
  EXPECT_TRUE(fs::exists(path("out.png"))) << "the preview beside the EXR";
}

// A bad reference or output folder is refused before the render starts: a 60-second render
// with a missing reference ends at once, without output (it used to render first, write the
// image and exit 1).
TEST_F(CliChecks, RenderRefusesABadReferenceOrOutputFolderBeforeItRenders) {
  const auto start = std::chrono::steady_clock::now();
  CliRun missing = run(dir_, {"render", scene_, "--seconds", "60", "-o", path("out.exr"),
                              "--reference", path("nothing.exr")});
  EXPECT_NE(missing.code, 0);
  EXPECT_NE(missing.output.find("nothing.exr"), std::string::npos) << missing.output;
  Image small(8, 6);
  write_exr(path("small.exr"), small, nullptr, {});
  CliRun resolution = run(dir_, {"render", scene_, "--seconds", "60", "-o", path("out.exr"),
                                 "--reference", path("small.exr")});
  EXPECT_NE(resolution.code, 0);
  EXPECT_NE(resolution.output.find("8x6"), std::string::npos) << resolution.output;
  CliRun folder = run(dir_, {"render", scene_, "--seconds", "60", "-o", path("missing/out.exr")});
  EXPECT_NE(folder.code, 0);
  EXPECT_NE(folder.output.find("does not exist"), std::string::npos) << folder.output;
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(20))
      << "a refused render rendered first";
  EXPECT_FALSE(fs::exists(path("out.exr")));
  EXPECT_FALSE(fs::exists(path("out.png")));
}

// `penumbra verify`: an unbiased method passes against the exact reference (exit 0); against
// the exact reference of a scene whose light is 10% brighter (a reference EXR of another scene,
// accepted only with --accept-reference-mismatch) it fails with exit code 4, naming the blocks.
TEST_F(CliChecks, VerifyPassesAnUnbiasedMethodAndFlagsABiasedReference) {
  CliRun pass = run(dir_, {"verify", scene_, "-m", "sa", "--runs", "3", "--spp", "8", "--width",
                           "0", "--block", "4", "--json", path("verify.json")});
  ASSERT_EQ(pass.code, 0) << pass.output;
  EXPECT_NE(pass.output.find("PASS: no block beyond 5 sigma"), std::string::npos) << pass.output;
  EXPECT_NE(pass.output.find("Bonferroni"), std::string::npos);
  EXPECT_NE(read_text(path("verify.json")).find("\"format\": \"penumbra/verify-result@1\""),
            std::string::npos);
  const std::string bright = write("bright.json", scene_json(16, 12, "", "", "", "", 5.5));
  CliRun reference =
      run(dir_, {"exact-reference", bright, "-o", path("bright.exr"), "--camera-samples", "16"});
  ASSERT_EQ(reference.code, 0) << reference.output;
  CliRun refused = run(dir_, {"verify", scene_, "-m", "sa", "--reference", path("bright.exr")});
  EXPECT_EQ(refused.code, 1) << refused.output;
  EXPECT_NE(refused.output.find("--accept-reference-mismatch"), std::string::npos);
  CliRun fail = run(dir_, {"verify", scene_, "-m", "sa", "--runs", "3", "--spp", "8", "--block",
                           "4", "--reference", path("bright.exr"), "--accept-reference-mismatch"});
  EXPECT_EQ(fail.code, 4) << fail.output;
  EXPECT_NE(fail.output.find("FAIL: "), std::string::npos) << fail.output;
  // 1 / 1.1 - 1 = -9.1% in every block, about 14 standard errors: the worst block is below.
  EXPECT_NE(fail.output.find("largest |z|: block"), std::string::npos);
  EXPECT_NE(fail.output.find(", z = -"), std::string::npos) << fail.output;
}

TEST_F(CliChecks, OptionsAreCheckedAndTheirDefaultsShown) {
  CliRun seed = run(dir_, {"render", scene_, "--spp", "1", "-o", path("s.exr"), "--seed", "-1"});
  EXPECT_NE(seed.code, 0);
  EXPECT_NE(seed.output.find("the seed is an integer"), std::string::npos) << seed.output;
  EXPECT_FALSE(fs::exists(path("s.exr")));
  CliRun seconds = run(dir_, {"render", scene_, "--seconds", "0"});
  EXPECT_NE(seconds.code, 0);
  EXPECT_NE(seconds.output.find("--seconds"), std::string::npos) << seconds.output;
  EXPECT_LT(seconds.output.size(), 400u) << "a 309-digit bound? " << seconds.output;
  // Both budgets: render stops at whichever comes first, and says so; submit refuses (below).
  CliRun both =
      run(dir_, {"render", scene_, "--spp", "2", "--seconds", "100", "-o", path("both.exr")});
  ASSERT_EQ(both.code, 0) << both.output;
  EXPECT_NE(both.output.find("--seconds 100 with --spp 2: renders until either is reached"),
            std::string::npos)
      << both.output;
  ImageMetadata metadata;
  read_exr(path("both.exr"), &metadata);
  EXPECT_EQ(metadata["penumbra:spp"], "2") << "--spp was ignored";
  // The defaults are in --help.
  CliRun render_help = run(dir_, {"render", "--help"});
  for (const char* text : {"the scene's own, else sa", "the scene's own, else stratified",
                           "the scene's, else 16", "out.exr"})
    EXPECT_NE(render_help.output.find(text), std::string::npos) << text << "\n"
                                                                << render_help.output;
    // `submit`, `list` and the other farm commands exist only in a build with the farm.
#if !__has_include("penumbra/v1/farm.pb.h")
  GTEST_SKIP() << "the farm commands are not built (PENUMBRA_FARM=OFF); render's checks passed";
#endif
  CliRun zero = run(dir_, {"submit", scene_, "--spp", "0"});
  EXPECT_NE(zero.code, 0);
  EXPECT_NE(zero.output.find("--spp"), std::string::npos) << zero.output;
  EXPECT_EQ(zero.output.find("exactly one budget"), std::string::npos) << zero.output;
  CliRun budgets = run(dir_, {"submit", scene_, "--spp", "4", "--seconds", "2"});
  EXPECT_NE(budgets.code, 0);
  EXPECT_NE(budgets.output.find("--spp and --seconds both given"), std::string::npos)
      << budgets.output;
  CliRun help = run(dir_, {"submit", "--help"});
  EXPECT_NE(help.output.find("-m,--method"), std::string::npos) << help.output;
  EXPECT_NE(help.output.find("-s,--sampler"), std::string::npos);
  EXPECT_NE(help.output.find("else stratified"), std::string::npos);
  // No coordinator: the error, without a table header before it.
  CliRun list = run(dir_, {"list", "--coordinator", "127.0.0.1:1"});
  EXPECT_NE(list.code, 0);
  EXPECT_EQ(list.output.find("STATE"), std::string::npos) << list.output;
}

}  // namespace
}  // namespace penumbra
