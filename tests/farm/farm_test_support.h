#pragma once
// Helpers for the farm's integration tests: child processes (coordinator, workers) on loopback,
// a small scene written to a temporary folder, and a local render to compare against.

#include <arpa/inet.h>
#include <fcntl.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <memory>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "core/image/image.h"
#include "core/render/film.h"
#include "core/render/renderer.h"
#include "core/sampling/pattern.h"
#include "core/scene/scene.h"
#include "proto/support/farm_client.h"
#include "proto/support/scene_packing.h"

namespace penumbra::farm::testing {

inline std::string binary(const std::string& relative) {
  return std::string(PENUMBRA_BINARY_DIR) + "/" + relative;
}

// A TCP port on 127.0.0.1 that was free a moment ago (the kernel's choice for port 0).
inline int free_port() {
  int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  address.sin_port = 0;
  socklen_t length = sizeof address;
  if (fd < 0 || ::bind(fd, reinterpret_cast<sockaddr*>(&address), sizeof address) != 0 ||
      ::getsockname(fd, reinterpret_cast<sockaddr*>(&address), &length) != 0)
    throw std::runtime_error("cannot find a free port");
  int port = ntohs(address.sin_port);
  ::close(fd);
  return port;
}

inline std::filesystem::path fresh_directory(const std::string& name) {
  std::random_device random;
  auto dir = std::filesystem::temp_directory_path() /
             ("penumbra-farm-" + name + "-" + std::to_string(::getpid()) + "-" +
              std::to_string(random() % 100000));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

// A child process with its output in a log file; killed (SIGKILL) when destroyed if still running.
class ChildProcess {
 public:
  ChildProcess(const std::vector<std::string>& arguments, const std::string& log_path) {
    // Everything the child needs is prepared before fork: the parent has threads, so the child
    // may only make async-signal-safe calls until exec.
    std::vector<char*> argv;
    for (const std::string& argument : arguments)
      argv.push_back(const_cast<char*>(argument.c_str()));
    argv.push_back(nullptr);
    int fd = ::open(log_path.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
    pid_ = ::fork();
    if (pid_ < 0) throw std::runtime_error("fork failed");
    if (pid_ == 0) {
      if (fd >= 0) {
        ::dup2(fd, 1);
        ::dup2(fd, 2);
      }
      ::execv(argv[0], argv.data());
      ::_exit(127);
    }
    if (fd >= 0) ::close(fd);
  }
  ~ChildProcess() {
    if (running()) {
      ::kill(pid_, SIGKILL);
      wait_exit(std::chrono::seconds(10));
    }
  }
  ChildProcess(const ChildProcess&) = delete;
  ChildProcess& operator=(const ChildProcess&) = delete;

  bool running() { return poll(); }
  void signal(int number) { ::kill(pid_, number); }
  // The exit code (or -signal) once it exits within `timeout`; throws otherwise.
  int wait_exit(std::chrono::milliseconds timeout) {
    auto deadline = std::chrono::steady_clock::now() + timeout;
    while (poll()) {
      if (std::chrono::steady_clock::now() > deadline)
        throw std::runtime_error("child " + std::to_string(pid_) + " did not exit in time");
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    return exit_code_;
  }

 private:
  bool poll() {
    if (exited_) return false;
    int status = 0;
    if (::waitpid(pid_, &status, WNOHANG) == pid_) {
      exited_ = true;
      exit_code_ = WIFEXITED(status) ? WEXITSTATUS(status) : -WTERMSIG(status);
      return false;
    }
    return true;
  }
  pid_t pid_ = -1;
  bool exited_ = false;
  int exit_code_ = 0;
};

// A scene small enough for tests: a floor, an occluder box, a quad light, `width` x `height`.
inline std::string small_scene_json(int width, int height) {
  std::ostringstream json;
  json << R"({
  "format": "penumbra/scene@1",
  "name": "farm-test",
  "camera": { "position": [0, 1.2, 3.0], "look_at": [0, 0.3, 0], "up": [0, 1, 0],
              "fov_y_deg": 40, "width": )"
       << width << R"(, "height": )" << height << R"( },
  "materials": { "white": { "type": "lambert", "albedo": [0.8, 0.8, 0.8] },
                 "red": { "type": "lambert", "albedo": [0.7, 0.1, 0.1] } },
  "shapes": [
    { "type": "quad", "origin": [-2, 0, 2], "edge1": [4, 0, 0], "edge2": [0, 0, -4], "material": "white" },
    { "type": "box", "min": [-0.3, 0.4, -0.3], "max": [0.3, 0.5, 0.3], "material": "red" }
  ],
  "lights": [
    { "type": "quad", "origin": [-0.5, 1.5, -0.5], "edge1": [1, 0, 0], "edge2": [0, 0, 1],
      "radiance": [5, 5, 5] }
  ],
  "regions": { "shadow": [8, 8, 24, 24] }
})";
  return json.str();
}

inline std::string write_scene(const std::filesystem::path& dir, int width, int height) {
  auto path = dir / "farm-test.json";
  std::ofstream(path) << small_scene_json(width, height);
  return path.string();
}

inline v1::JobSpec job_spec(const std::string& scene_path, const std::string& method, uint32_t spp,
                            uint64_t seed, uint32_t tile_size = 16, uint32_t passes_per_task = 4) {
  v1::JobSpec spec;
  *spec.mutable_scene() = pack_scene_file(scene_path);
  spec.set_method(method);
  spec.set_sampler("stratified");
  spec.set_seed(seed);
  spec.set_spp(spp);
  spec.set_tile_size(tile_size);
  spec.set_passes_per_task(passes_per_task);
  return spec;
}

// The same job rendered in this process, in one piece per 64x64 tile (other tiles and pass
// ranges than the farm's: the sums are exact, so the images must agree bit for bit).
inline Film render_locally(const std::string& scene_path, const std::string& method,
                           const std::string& sampler, uint32_t spp, uint64_t seed) {
  auto scene = std::make_shared<const Scene>(load_scene(scene_path));
  RenderOptions options;
  options.method = method;
  options.sampler = parse_pattern(sampler).value();
  options.seed = seed;
  Renderer renderer(scene, options);
  std::vector<TileAccumulator> tiles;
  for (const TileRect& rect : cut_tiles(scene->camera.width, scene->camera.height, 64)) {
    tiles.emplace_back(rect);
    renderer.render_tile(rect, 0, spp, tiles.back());
  }
  return assemble_film(scene->camera.width, scene->camera.height, tiles);
}

inline bool same_bits(const Image& a, const Image& b) {
  return a.width == b.width && a.height == b.height && a.rgb.size() == b.rgb.size() &&
         std::memcmp(a.rgb.data(), b.rgb.data(), a.rgb.size() * sizeof(float)) == 0;
}

// A coordinator process on 127.0.0.1 with a short lease time. kill() and restart() SIGKILL it and
// start it again on the same data directory, port and arguments (the workers reconnect by
// themselves).
class CoordinatorProcess {
 public:
  CoordinatorProcess(const std::filesystem::path& data_dir, int port = 0,
                     std::vector<std::string> extra = {}, double lease_seconds = 1.0)
      : data_dir_(data_dir), extra_(std::move(extra)), lease_seconds_(lease_seconds) {
    start(port);
  }
  int port() const { return port_; }
  std::string address() const { return "127.0.0.1:" + std::to_string(port_); }
  ChildProcess& process() { return *process_; }  // not between kill() and restart()

  // SIGKILL, and wait until it has exited.
  void kill() {
    if (!process_) return;
    process_->signal(SIGKILL);
    process_->wait_exit(std::chrono::seconds(10));
    process_.reset();
  }
  // kill() if it still runs, then start it again; returns once it listens.
  void restart() {
    kill();
    start(port_);
  }

 private:
  void start(int port) {
    auto port_file = data_dir_ / "port";
    std::filesystem::create_directories(data_dir_);
    std::filesystem::remove(port_file);
    std::vector<std::string> arguments = {binary("server/penumbra-coordinator"),
                                          "--listen",
                                          "127.0.0.1:" + std::to_string(port),
                                          "--data-dir",
                                          data_dir_.string(),
                                          "--port-file",
                                          port_file.string(),
                                          "--lease-seconds",
                                          std::to_string(lease_seconds_)};
    arguments.insert(arguments.end(), extra_.begin(), extra_.end());
    process_ = std::make_unique<ChildProcess>(arguments, (data_dir_ / "coordinator.log").string());
    auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
    while (!std::filesystem::exists(port_file)) {
      if (!process_->running() || std::chrono::steady_clock::now() > deadline)
        throw std::runtime_error("coordinator did not start; see " +
                                 (data_dir_ / "coordinator.log").string());
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    std::ifstream(port_file) >> port_;
  }

  std::filesystem::path data_dir_;
  std::vector<std::string> extra_;
  double lease_seconds_;
  std::unique_ptr<ChildProcess> process_;
  int port_ = 0;
};

inline std::unique_ptr<ChildProcess> start_worker(const std::string& address,
                                                  const std::filesystem::path& dir,
                                                  const std::string& name, int threads = 1) {
  return std::make_unique<ChildProcess>(
      std::vector<std::string>{binary("worker/penumbra-worker"), "--coordinator", address,
                               "--threads", std::to_string(threads), "--cache-dir",
                               (dir / ("cache-" + name)).string(), "--name", name},
      (dir / (name + ".log")).string());
}

// start_worker with further arguments (TLS, token) after the usual ones.
inline std::unique_ptr<ChildProcess> start_worker_with(const std::string& address,
                                                       const std::filesystem::path& dir,
                                                       const std::string& name,
                                                       const std::vector<std::string>& extra,
                                                       int threads = 1) {
  std::vector<std::string> arguments = {binary("worker/penumbra-worker"),
                                        "--coordinator",
                                        address,
                                        "--threads",
                                        std::to_string(threads),
                                        "--cache-dir",
                                        (dir / ("cache-" + name)).string(),
                                        "--name",
                                        name};
  arguments.insert(arguments.end(), extra.begin(), extra.end());
  return std::make_unique<ChildProcess>(arguments, (dir / (name + ".log")).string());
}

inline void expect_bit_identical(FarmClient& client, const std::string& job_id,
                                 const std::string& scene_path, const std::string& method,
                                 uint32_t spp, uint64_t seed) {
  ImageMetadata metadata;
  Image variance;
  Image color = decode_exr(client.fetch(job_id), &metadata, &variance);
  Film local = render_locally(scene_path, method, "stratified", spp, seed);
  EXPECT_TRUE(same_bits(color, local.color)) << job_id << ": color differs";
  EXPECT_TRUE(same_bits(variance, local.variance)) << job_id << ": variance differs";
  EXPECT_EQ(metadata["penumbra:spp"], std::to_string(spp));
  EXPECT_EQ(metadata["penumbra:method"], method);
}

// Waits until `count` workers have registered (a job submitted earlier may be over before a
// slow-starting worker joins); throws after `timeout`.
inline void wait_for_workers(FarmClient& client, size_t count,
                             std::chrono::milliseconds timeout = std::chrono::seconds(60)) {
  auto deadline = std::chrono::steady_clock::now() + timeout;
  while (client.workers().size() < count) {
    if (std::chrono::steady_clock::now() > deadline)
      throw std::runtime_error(std::to_string(count) + " workers did not register in time");
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
}

inline v1::JobStatus wait_until(FarmClient& client, const std::string& job_id,
                                const std::function<bool(const v1::JobStatus&)>& condition,
                                std::chrono::milliseconds timeout = std::chrono::seconds(60)) {
  auto deadline = std::chrono::steady_clock::now() + timeout;
  while (true) {
    v1::JobStatus status = client.status(job_id);
    if (condition(status)) return status;
    if (std::chrono::steady_clock::now() > deadline)
      throw std::runtime_error(job_id + ": condition not reached in time; state " +
                               v1::JobState_Name(status.state()));
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
}

}  // namespace penumbra::farm::testing
