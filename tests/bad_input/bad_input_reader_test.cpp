// The bad-input corpus (tests/data/bad_input/) against the readers in this process and the
// command-line client: every scene, method and batch case is refused with a FormatError whose
// message names what is wrong, and `penumbra render` on each bad scene exits non-zero printing
// it. The same corpus against live coordinator and worker processes: bad_input_test.cpp.

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <cstdlib>
#include <filesystem>
#include <thread>
#include <vector>

#include "bad_input_cases.h"
#include "core/method/method.h"
#include "core/scene/scene.h"
#include "core/scene/scene_package.h"
#if __has_include("core/batch/batch_spec.h")
#include "core/batch/batch_spec.h"
#define PENUMBRA_HAS_BATCH_READER 1
#endif

namespace penumbra::bad_input {
namespace {

// The message of the FormatError `read` throws, or "" (with a test failure) when it does not.
template <typename Read>
std::string format_error_of(const std::string& name, Read read) {
  try {
    read();
  } catch (const FormatError& error) {
    return error.what();
  } catch (const std::exception& error) {
    ADD_FAILURE() << name << ": threw something else than FormatError: " << error.what();
    return "";
  }
  ADD_FAILURE() << name << ": accepted";
  return "";
}

TEST(BadInputReaders, EveryCaseHasAnExpectation) {
  for (const char* folder : {"scenes", "methods", "batches", "requests"}) {
    auto cases = load_cases(folder);
    EXPECT_FALSE(cases.empty()) << folder;
    for (const BadInputCase& c : cases) {
      EXPECT_FALSE(c.status().empty()) << c.name << ": no status";
      EXPECT_TRUE(c.get("message")) << c.name << ": no message";
    }
  }
}

TEST(BadInputReaders, ScenesFromDiskAndFromPackagesAreRefusedNamingTheProblem) {
  auto cases = load_cases("scenes");
  for (const BadInputCase& c : cases) {
    SCOPED_TRACE(c.name);
    // From disk (the CLI's and the client packer's route).
    std::string message = format_error_of(c.name, [&] { load_scene(c.path.string()); });
    EXPECT_NE(message.find(c.message()), std::string::npos) << message;
    message = format_error_of(c.name, [&] { collect_scene_package(c.path.string()); });
    EXPECT_NE(message.find(c.message()), std::string::npos) << message;
    // From a package in memory (the coordinator's and the workers' route).
    if (c.get("wire") == "none") continue;
    ScenePackage package;
    package.source = c.path.filename().string();
    package.scene_json = c.text();
    package.files = c.package_files();
    message = format_error_of(c.name, [&] { parse_scene_package(package); });
    EXPECT_NE(message.find(c.message()), std::string::npos) << message;
  }
}

TEST(BadInputReaders, MethodsAreRefusedNamingTheProblem) {
  for (const BadInputCase& c : load_cases("methods")) {
    std::string message = format_error_of(c.name, [&] { parse_method(c.text()); });
    EXPECT_NE(message.find(c.message()), std::string::npos) << c.name << ": " << message;
  }
}

TEST(BadInputReaders, BatchesAreRefusedNamingTheProblem) {
#ifdef PENUMBRA_HAS_BATCH_READER
  for (const BadInputCase& c : load_cases("batches")) {
    std::string message =
        format_error_of(c.name, [&] { parse_batch_spec(c.text(), c.path.filename().string()); });
    EXPECT_NE(message.find(c.message()), std::string::npos) << c.name << ": " << message;
  }
#else
  GTEST_SKIP() << "core/batch/batch_spec.h is not in this tree";
#endif
}

TEST(BadInputCli, RenderExitsNonZeroNamingTheProblemForEveryBadScene) {
  const std::string binary = std::string(PENUMBRA_BINARY_DIR) + "/client/penumbra";
  ASSERT_TRUE(std::filesystem::exists(binary)) << binary;
  auto out = std::filesystem::temp_directory_path() /
             ("penumbra-bad-input-cli-" + std::to_string(::getpid()));
  std::filesystem::create_directories(out);
  auto cases = load_cases("scenes");
  // One process per case, 4 at a time: the time goes into starting the program, not into it.
  std::vector<int> statuses(cases.size());
  std::atomic<size_t> next{0};
  auto run_cases = [&] {
    for (size_t i = next++; i < cases.size(); i = next++) {
      const std::string stem = cases[i].path.filename().string();
      std::string command = "'" + binary + "' render '" + cases[i].path.string() +
                            "' --spp 1 -o '" + (out / (stem + ".exr")).string() + "' >'" +
                            (out / (stem + ".log")).string() + "' 2>&1";
      statuses[i] = std::system(command.c_str());
    }
  };
  std::vector<std::thread> threads;
  for (int t = 0; t < 4; ++t) threads.emplace_back(run_cases);
  for (std::thread& thread : threads) thread.join();
  for (size_t i = 0; i < cases.size(); ++i) {
    const BadInputCase& c = cases[i];
    const std::string stem = c.path.filename().string();
    std::string printed = read_bytes(out / (stem + ".log"));
    int status = statuses[i];
    EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) != 0)
        << c.name << ": exit status " << status << "\n"
        << printed;
    EXPECT_NE(printed.find("penumbra: error: "), std::string::npos) << c.name << ": " << printed;
    EXPECT_NE(printed.find(c.message()), std::string::npos) << c.name << ": " << printed;
    EXPECT_FALSE(std::filesystem::exists(out / (stem + ".exr"))) << c.name << ": wrote an image";
  }
  std::filesystem::remove_all(out);
}

}  // namespace
}  // namespace penumbra::bad_input
