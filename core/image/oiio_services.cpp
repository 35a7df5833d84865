#include "core/image/oiio_services.h"

#include <dlfcn.h>
#include <unistd.h>

#include <atomic>
#include <cstdlib>
#include <filesystem>
#include <mutex>
#include <stdexcept>
#include <system_error>

namespace penumbra::oiio {

namespace {

std::atomic<const Services*> g_services{nullptr};
std::mutex g_load_mutex;

// Where the module may be, in the order tried.
std::vector<std::string> candidate_paths() {
  std::vector<std::string> paths;
  // A path the user names is the only one tried.
  if (const char* explicit_path = std::getenv("PENUMBRA_OIIO_MODULE");
      explicit_path && *explicit_path)
    return {explicit_path};
  std::error_code error;
  std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", error);
  if (!error) {
    paths.push_back((exe.parent_path() / kModuleFile).string());
    paths.push_back(
        (exe.parent_path() / ".." / "lib" / "penumbra" / kModuleFile).lexically_normal().string());
  }
#ifdef PENUMBRA_OIIO_MODULE_BUILD_PATH
  paths.emplace_back(PENUMBRA_OIIO_MODULE_BUILD_PATH);
#endif
  paths.emplace_back(kModuleFile);  // the dynamic linker's search path
  return paths;
}

const Services* load() {
  using Entry = const Services* (*)(int);
  std::string tried;
  for (const std::string& path : candidate_paths()) {
    bool bare = path.find('/') == std::string::npos;
    if (!bare && !std::filesystem::exists(path)) {
      tried += "\n  " + path + ": no such file";
      continue;
    }
    void* module = ::dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
    if (!module) {
      const char* why = ::dlerror();
      tried += "\n  " + path + ": " + (why ? why : "cannot be loaded");
      continue;
    }
    auto entry = reinterpret_cast<Entry>(::dlsym(module, kEntryPoint));
    if (!entry) {
      tried += "\n  " + path + ": no " + kEntryPoint;
      continue;
    }
    const Services* services = entry(kInterfaceVersion);
    if (!services) {
      tried += "\n  " + path + ": built for another version of the interface";
      continue;
    }
    // The module stays loaded for the life of the process (its objects are referenced from
    // static storage and thread-locals).
    return services;
  }
  throw std::runtime_error(std::string("cannot load the image module ") + kModuleFile +
                           " (OpenImageIO), tried:" + tried +
                           "\n(set PENUMBRA_OIIO_MODULE to its path)");
}

}  // namespace

const Services& services() {
  if (const Services* loaded = g_services.load(std::memory_order_acquire)) return *loaded;
  std::lock_guard lock(g_load_mutex);
  if (const Services* loaded = g_services.load(std::memory_order_relaxed)) return *loaded;
  const Services* services = load();
  g_services.store(services, std::memory_order_release);
  return *services;
}

bool loaded() {
  return g_services.load(std::memory_order_acquire) != nullptr;
}

}  // namespace penumbra::oiio
