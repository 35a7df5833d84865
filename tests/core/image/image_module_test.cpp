// The image module (core/image/oiio_services.h): OpenImageIO is not in a process until its first
// image, and a module that cannot be found is an error naming where it was looked for.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>

#include "core/image/image.h"
#include "core/image/oiio_services.h"

namespace penumbra {
namespace {

bool mapped(const std::string& library) {
  std::ifstream maps("/proc/self/maps");
  std::stringstream text;
  text << maps.rdbuf();
  return text.str().find(library) != std::string::npos;
}

TEST(ImageModule, OpenImageIOIsLoadedWithTheFirstImageOnly) {
  ASSERT_FALSE(oiio::loaded());
  EXPECT_FALSE(mapped("libOpenImageIO")) << "a test program of core/image links OpenImageIO";
  Image image(4, 2);
  image.set(1, 1, {0.5, 0.25, 1.0});
  std::string png = encode_png_preview(image);
  ASSERT_GT(png.size(), 8u);
  EXPECT_EQ(png.substr(1, 3), "PNG");
  EXPECT_TRUE(oiio::loaded());
  EXPECT_TRUE(mapped("libpenumbra_oiio.so"));
  EXPECT_TRUE(mapped("libOpenImageIO"));
  // The EXR round trip goes through the same module.
  Image back = decode_exr(encode_exr(image, nullptr, {{"method", "sa"}}));
  EXPECT_EQ(back.rgb, image.rgb);
}

TEST(ImageModule, AModuleThatCannotBeFoundIsAnErrorNamingThePath) {
  // A process of its own: the module loads once per process.
  pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    ::setenv("PENUMBRA_OIIO_MODULE", "/nonexistent/libpenumbra_oiio.so", 1);
    int code = 3;
    try {
      encode_png_preview(Image(1, 1));
    } catch (const std::runtime_error& error) {
      std::string message = error.what();
      code = message.find("PNG encoding: cannot load the image module") == 0 &&
                     message.find("/nonexistent/libpenumbra_oiio.so: no such file") !=
                         std::string::npos
                 ? 0
                 : 4;
    }
    std::_Exit(code);
  }
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0) << "3: no error; 4: an error without the path";
}

}  // namespace
}  // namespace penumbra
