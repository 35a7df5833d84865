#pragma once
// Shared by the image tests (chart_test.cpp, image_io_test.cpp): a folder for the files a test
// program writes, made on first use and removed when the program ends.

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <string>

namespace penumbra::image_test {

// $TMPDIR/penumbra_image_test_<pid>: one per process (ctest runs each test in its own).
inline std::filesystem::path test_directory() {
  static std::filesystem::path directory = [] {
    std::filesystem::path dir = std::filesystem::temp_directory_path() /
                                ("penumbra_image_test_" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir);
    return dir;
  }();
  return directory;
}

class RemoveTestDirectory : public ::testing::Environment {
 public:
  void TearDown() override { std::filesystem::remove_all(test_directory()); }
};
inline const ::testing::Environment* const kRemoveTestDirectory =
    ::testing::AddGlobalTestEnvironment(new RemoveTestDirectory);

}  // namespace penumbra::image_test
