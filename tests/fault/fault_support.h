#pragma once
// Helpers for the fault tests (tests/fault/): an in-process coordinator whose counters the test
// reads, worker processes inside Linux network namespaces joined to this one by a veth pair,
// packet loss on that veth (nftables `numgen random`: this kernel has no netem qdisc), a TCP
// relay that delays every chunk (the latency netem would add), measurements that the delay and
// the loss are really there, the check that every job finished bit-identical to a local render,
// and the table of faults the tests print.
//
// Builds on tests/farm/farm_test_support.h (child processes, scenes, local renders).

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sched.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <cstdio>
#include <cstdlib>
#include <deque>
#include <functional>
#include <map>
#include <mutex>
#include <optional>
#include <random>
#include <tuple>

#include "../farm/farm_test_support.h"
#include "proto/support/scene_packing.h"
#include "server/coordinator.h"
#include "server/coordinator_server.h"

namespace penumbra::farm::fault {

using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;

inline double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// Runs a shell command; returns its exit status (0: success).
inline int shell(const std::string& command) {
  int status = std::system(("( " + command + " ) >/dev/null 2>&1").c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

inline void shell_or_throw(const std::string& command) {
  if (shell(command) != 0) throw std::runtime_error("command failed: " + command);
}

// Network namespaces, veth and nftables need root (and a kernel that has them).
inline std::string root_network_missing() {
  if (::geteuid() != 0) return "needs root (network namespaces, veth, nftables, tmpfs mounts)";
  if (shell("command -v ip && command -v nft") != 0) return "needs iproute2 and nftables";
  return "";
}

#define PENUMBRA_REQUIRE_ROOT_NETWORK()                                      \
  do {                                                                       \
    std::string missing = ::penumbra::farm::fault::root_network_missing();   \
    if (!missing.empty()) GTEST_SKIP() << "fault test skipped: " << missing; \
  } while (false)

// ---------------------------------------------------------------------------------------------
// The table of faults

struct FaultRow {
  std::string fault;
  int injections = 0;
  int jobs = 0;
  int lost_jobs = 0;
  int mismatched_images = 0;
};

inline std::vector<FaultRow>& fault_rows() {
  static std::vector<FaultRow> rows;
  return rows;
}

inline void print_fault_table(const std::vector<FaultRow>& rows) {
  std::printf("\n%-44s %10s %5s %9s %17s\n", "fault", "injections", "jobs", "lost jobs",
              "mismatched images");
  for (const FaultRow& row : rows)
    std::printf("%-44s %10d %5d %9d %17d\n", row.fault.c_str(), row.injections, row.jobs,
                row.lost_jobs, row.mismatched_images);
  std::fflush(stdout);
}

// Prints the row now (ctest runs each test in a process of its own) and keeps it for the table
// the program prints at its end when it runs every test itself.
inline void record_fault_row(const FaultRow& row) {
  fault_rows().push_back(row);
  print_fault_table({row});
}

class FaultTableEnvironment : public ::testing::Environment {
 public:
  void TearDown() override {
    if (fault_rows().size() > 1) print_fault_table(fault_rows());
  }
};

// ---------------------------------------------------------------------------------------------
// Jobs and their check against local renders

inline bool job_ended(v1::JobState state) {
  return state == v1::JOB_STATE_DONE || state == v1::JOB_STATE_FAILED ||
         state == v1::JOB_STATE_CANCELLED;
}

struct SubmittedJob {
  std::string id;
  std::string method;
  uint32_t spp = 0;
  uint64_t seed = 0;
};

// Waits for every job to end (reconnecting while the coordinator is away), then compares each
// finished job's EXR (color and variance) with a local render bit for bit. Fills the row's jobs,
// lost jobs (not DONE in time) and mismatched images.
inline void check_jobs(const std::string& address, const std::string& scene_path,
                       const std::vector<SubmittedJob>& jobs, FaultRow& row,
                       std::chrono::seconds timeout = 90s) {
  FarmClient client(address);
  std::map<std::tuple<std::string, uint32_t, uint64_t>, Film> local;
  auto deadline = Clock::now() + timeout;
  row.jobs = int(jobs.size());
  for (const SubmittedJob& job : jobs) {
    v1::JobStatus status;
    bool done = false;
    while (Clock::now() < deadline) {
      try {
        status = client.status(job.id);
        if (job_ended(status.state())) {
          done = status.state() == v1::JOB_STATE_DONE;
          break;
        }
      } catch (const FarmCallError&) {
        // The coordinator is restarting: ask again.
      }
      std::this_thread::sleep_for(20ms);
    }
    if (!done) {
      ++row.lost_jobs;
      ADD_FAILURE() << job.id << " did not finish: " << v1::JobState_Name(status.state()) << " "
                    << status.error();
      continue;
    }
    auto key = std::make_tuple(job.method, job.spp, job.seed);
    if (!local.count(key))
      local.emplace(
          key, testing::render_locally(scene_path, job.method, "stratified", job.spp, job.seed));
    const Film& reference = local.at(key);
    ImageMetadata metadata;
    Image variance;
    Image color = decode_exr(client.fetch(job.id), &metadata, &variance);
    bool same = testing::same_bits(color, reference.color) &&
                testing::same_bits(variance, reference.variance) &&
                metadata["penumbra:spp"] == std::to_string(job.spp);
    if (!same) {
      ++row.mismatched_images;
      ADD_FAILURE() << job.id << ": the image differs from the local render";
    }
  }
}

// ---------------------------------------------------------------------------------------------
// A coordinator in this process (its counters() are the test's to read) on `listen`.

class InProcessCoordinator {
 public:
  InProcessCoordinator(const std::filesystem::path& data_dir, std::chrono::milliseconds lease,
                       const std::string& listen = "127.0.0.1:0") {
    CoordinatorOptions options;
    options.data_dir = data_dir.string();
    options.lease_time = lease;
    coordinator_ = std::make_unique<Coordinator>(options, parse_wire_package);
    server_ = std::make_unique<CoordinatorServer>(*coordinator_, listen, size_t(64) << 20);
  }
  ~InProcessCoordinator() {
    server_.reset();
    coordinator_.reset();
  }
  int port() const { return server_->port(); }
  std::string address() const { return "127.0.0.1:" + std::to_string(port()); }
  Coordinator& coordinator() { return *coordinator_; }

  // The coordinator's view of a worker by name (summed over its registrations).
  uint64_t leased_by(const std::string& name) {
    uint64_t leased = 0;
    for (const v1::WorkerInfo& worker : coordinator_->workers())
      if (worker.name() == name) leased += worker.tasks_leased();
    return leased;
  }
  uint64_t completed_by_all() {
    uint64_t completed = 0;
    for (const v1::WorkerInfo& worker : coordinator_->workers())
      completed += worker.tasks_completed();
    return completed;
  }

 private:
  std::unique_ptr<Coordinator> coordinator_;
  std::unique_ptr<CoordinatorServer> server_;
};

// "w<w>", or "w<w>-<restart>" for a restarted one. (Appended rather than "w" + std::to_string(w):
// GCC 12 warns falsely, -Wrestrict, on that operator+ when inlined.)
inline std::string worker_name(int w, int restart = 0) {
  std::string name = "w";
  name += std::to_string(w);
  if (restart > 0) name.append("-").append(std::to_string(restart));
  return name;
}

// ---------------------------------------------------------------------------------------------
// The coordinator-kill tests: a coordinator process (lease 1 s) and two single-thread worker
// processes on loopback (no root needed), the small 64x64 scene in a fresh folder.

struct CoordinatorKillFarm {
  explicit CoordinatorKillFarm(const std::string& name, int worker_count = 2)
      : dir(testing::fresh_directory(name)),
        scene(testing::write_scene(dir, 64, 64)),
        coordinator(dir / "data", 0, {}, 1.0),
        address(coordinator.address()) {
    for (int w = 0; w < worker_count; ++w)
      workers.push_back(testing::start_worker(address, dir, worker_name(w)));
  }
  std::filesystem::path dir;
  std::string scene;
  testing::CoordinatorProcess coordinator;
  std::string address;  // the same across restarts
  std::vector<std::unique_ptr<testing::ChildProcess>> workers;
};

// What the coordinator's jobs have done so far (one ListJobs call).
struct FarmProgress {
  uint64_t sealed_passes = 0;              // summed over every job
  int unfinished_jobs = 0;                 // not yet ended
  bool part_way = false;                   // a job has sealed some passes and is not done
  std::map<std::string, uint32_t> passes;  // job id -> passes sealed
};

inline FarmProgress farm_progress(FarmClient& client) {
  FarmProgress progress;
  for (const v1::JobStatus& job : client.list()) {
    progress.sealed_passes += job.passes_complete();
    progress.passes[job.job_id()] = job.passes_complete();
    if (job_ended(job.state())) continue;
    ++progress.unfinished_jobs;
    progress.part_way |= job.passes_complete() > 0;
  }
  return progress;
}

// Kills the coordinator (SIGKILL) and restarts it on its data directory and port, `wanted`
// times. Each kill follows the work, not the clock: it comes once the jobs have sealed a random
// 1..max_passes_between more passes since the last (re)start while a job is part-way, so a fast
// machine cannot finish the work before the kills and a slow one only takes longer.
// `keep_busy` sees the jobs at every look (every few milliseconds) and may submit more work;
// `work_ended` says that no more will come (the kills stop short). After each restart every job
// must still be there with at least the passes it had sealed, none FAILED; `after_restart` adds
// the caller's checks. Returns the kills made: fewer than `wanted` only past `deadline` or once
// the work ended.
inline int kill_coordinator_on_progress(testing::CoordinatorProcess& coordinator, int wanted,
                                        uint32_t max_passes_between, std::mt19937& random,
                                        const std::function<void(const FarmProgress&)>& keep_busy,
                                        const std::function<bool()>& work_ended,
                                        const std::function<void()>& after_restart,
                                        std::chrono::seconds deadline) {
  const std::string address = coordinator.address();
  std::uniform_int_distribution<uint32_t> passes_between(1, max_passes_between);
  const auto start = Clock::now();
  auto client = std::make_unique<FarmClient>(address);
  uint64_t sealed_at_start = 0;
  int kills = 0;
  while (kills < wanted && Clock::now() - start < deadline && !work_ended()) {
    // Wait for that much progress with a job still part-way.
    const uint32_t wanted_passes = passes_between(random);
    FarmProgress before_kill;
    bool ready = false;
    while (!ready && Clock::now() - start < deadline && !work_ended()) {
      before_kill = farm_progress(*client);
      keep_busy(before_kill);
      ready = before_kill.part_way && before_kill.sealed_passes >= sealed_at_start + wanted_passes;
      if (!ready) std::this_thread::sleep_for(5ms);
    }
    if (!ready) break;
    coordinator.kill();
    ++kills;
    std::printf(
        "kill %d at %.1f s: %llu passes sealed (%u since the last start), %d jobs unfinished\n",
        kills, seconds_since(start), (unsigned long long)before_kill.sealed_passes,
        unsigned(before_kill.sealed_passes - sealed_at_start), before_kill.unfinished_jobs);
    coordinator.restart();
    // A new channel: the old one backs off after losing its connection.
    client = std::make_unique<FarmClient>(address);
    FarmProgress resumed = farm_progress(*client);
    for (const auto& [job, passes] : before_kill.passes) {
      EXPECT_TRUE(resumed.passes.count(job)) << job << " is gone after the restart";
      EXPECT_GE(resumed.passes[job], passes) << job << ": sealed passes were lost in the restart";
    }
    for (const v1::JobStatus& job : client->list())
      EXPECT_NE(job.state(), v1::JOB_STATE_FAILED) << job.job_id() << ": " << job.error();
    after_restart();
    sealed_at_start = resumed.sealed_passes;
  }
  return kills;
}

// ---------------------------------------------------------------------------------------------
// A network namespace joined to this one by a veth pair: host side 10.213.S.1/30 (in this
// namespace), namespace side 10.213.S.2/30. Names and the subnet depend on the process id and a
// counter so that tests running at the same time do not collide. Removed when destroyed.

class NetNamespace {
 public:
  NetNamespace() {
    static std::atomic<int> counter{0};
    int n = counter++;
    int id = (int(::getpid()) * 7 + n) % 100000;
    name_ = "pfault" + std::to_string(id);
    host_veth_ = "pfh" + std::to_string(id);
    ns_veth_ = "pfn" + std::to_string(id);
    int subnet = (int(::getpid()) + n * 37) % 63;  // 10.213.(4 * subnet).0/30
    host_ip_ = "10.213." + std::to_string(4 * subnet) + ".1";
    ns_ip_ = "10.213." + std::to_string(4 * subnet) + ".2";
    nft_table_ = "pfault" + std::to_string(id);
    shell("ip netns del " + name_);
    shell("ip link del " + host_veth_);
    shell_or_throw("ip netns add " + name_);
    shell_or_throw("ip link add " + host_veth_ + " type veth peer name " + ns_veth_);
    shell_or_throw("ip link set " + ns_veth_ + " netns " + name_);
    shell_or_throw("ip addr add " + host_ip_ + "/30 dev " + host_veth_);
    shell_or_throw("ip link set " + host_veth_ + " up");
    shell_or_throw("ip -n " + name_ + " addr add " + ns_ip_ + "/30 dev " + ns_veth_);
    shell_or_throw("ip -n " + name_ + " link set " + ns_veth_ + " up");
    shell_or_throw("ip -n " + name_ + " link set lo up");
  }
  ~NetNamespace() {
    shell("nft delete table inet " + nft_table_);
    shell("ip link del " + host_veth_);
    shell("ip netns del " + name_);
  }
  NetNamespace(const NetNamespace&) = delete;
  NetNamespace& operator=(const NetNamespace&) = delete;

  const std::string& name() const { return name_; }
  const std::string& host_ip() const { return host_ip_; }
  const std::string& ns_ip() const { return ns_ip_; }

  // Partition: the host side of the veth down (no packet passes either way), and back up.
  void set_link(bool up) { shell_or_throw("ip link set " + host_veth_ + (up ? " up" : " down")); }

  // Drops each packet crossing the veth, either way, with probability 1 / one_in (nftables'
  // `numgen random mod N == 0`, the equivalent of iptables' `statistic mode random`).
  void drop_randomly(int one_in) {
    std::string t = "inet " + nft_table_;
    shell_or_throw("nft add table " + t);
    shell_or_throw("nft 'add chain " + t + " in { type filter hook input priority 0; }'");
    shell_or_throw("nft 'add chain " + t + " out { type filter hook output priority 0; }'");
    std::string rule = " numgen random mod " + std::to_string(one_in) + " == 0 drop";
    shell_or_throw("nft add rule " + t + " in iifname " + host_veth_ + rule);
    shell_or_throw("nft add rule " + t + " out oifname " + host_veth_ + rule);
  }

  // Runs `body` on a thread that has joined this namespace (network namespaces are per thread).
  void run_inside(const std::function<void()>& body) const {
    std::exception_ptr error;
    std::thread thread([&] {
      try {
        int fd = ::open(("/var/run/netns/" + name_).c_str(), O_RDONLY | O_CLOEXEC);
        if (fd < 0 || ::setns(fd, CLONE_NEWNET) != 0)
          throw std::runtime_error("cannot enter namespace " + name_);
        ::close(fd);
        body();
      } catch (...) {
        error = std::current_exception();
      }
    });
    thread.join();
    if (error) std::rethrow_exception(error);
  }

  // A worker process inside the namespace.
  std::unique_ptr<testing::ChildProcess> start_worker(const std::string& address,
                                                      const std::filesystem::path& dir,
                                                      const std::string& name,
                                                      int threads = 1) const {
    return std::make_unique<testing::ChildProcess>(
        std::vector<std::string>{"/usr/sbin/ip", "netns", "exec", name_,
                                 testing::binary("worker/penumbra-worker"), "--coordinator",
                                 address, "--threads", std::to_string(threads), "--cache-dir",
                                 (dir / ("cache-" + name)).string(), "--name", name},
        (dir / (name + ".log")).string());
  }

 private:
  std::string name_, host_veth_, ns_veth_, host_ip_, ns_ip_, nft_table_;
};

// ---------------------------------------------------------------------------------------------
// Sockets

inline sockaddr_in socket_address(const std::string& ip, int port) {
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_port = htons(uint16_t(port));
  ::inet_pton(AF_INET, ip.c_str(), &address.sin_addr);
  return address;
}

inline int listening_socket(const std::string& ip, int* port) {
  int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  int one = 1;
  ::setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
  sockaddr_in address = socket_address(ip, 0);
  socklen_t length = sizeof address;
  if (::bind(fd, reinterpret_cast<sockaddr*>(&address), sizeof address) != 0 ||
      ::listen(fd, 64) != 0 ||
      ::getsockname(fd, reinterpret_cast<sockaddr*>(&address), &length) != 0) {
    ::close(fd);
    throw std::runtime_error("cannot listen on " + ip);
  }
  *port = ntohs(address.sin_port);
  return fd;
}

inline int connect_to(const std::string& ip, int port) {
  int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  sockaddr_in address = socket_address(ip, port);
  if (::connect(fd, reinterpret_cast<sockaddr*>(&address), sizeof address) != 0) {
    ::close(fd);
    return -1;
  }
  int one = 1;
  ::setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
  return fd;
}

// A TCP relay on listen_ip that forwards every connection to target_ip:target_port and delays
// every chunk, each way, by `delay` (in order): the one-way latency `tc netem delay` would add.
class DelayRelay {
 public:
  DelayRelay(const std::string& listen_ip, const std::string& target_ip, int target_port,
             std::chrono::milliseconds delay)
      : target_ip_(target_ip), target_port_(target_port), delay_(delay) {
    listen_fd_ = listening_socket(listen_ip, &port_);
    accept_thread_ = std::thread([this] { accept_loop(); });
  }
  ~DelayRelay() {
    stopping_ = true;
    accept_thread_.join();
    ::close(listen_fd_);
    std::lock_guard lock(mutex_);
    for (auto& pump : pumps_) pump.join();
    for (int fd : fds_) ::close(fd);
  }
  int port() const { return port_; }

 private:
  void accept_loop() {
    while (!stopping_) {
      pollfd p{listen_fd_, POLLIN, 0};
      if (::poll(&p, 1, 50) <= 0) continue;
      int client = ::accept4(listen_fd_, nullptr, nullptr, SOCK_CLOEXEC);
      if (client < 0) continue;
      int one = 1;
      ::setsockopt(client, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
      int server = connect_to(target_ip_, target_port_);
      if (server < 0) {
        ::close(client);
        continue;
      }
      std::lock_guard lock(mutex_);
      fds_.push_back(client);
      fds_.push_back(server);
      pumps_.emplace_back([this, client, server] { pump(client, server); });
      pumps_.emplace_back([this, client, server] { pump(server, client); });
    }
  }

  // Reads from `from`, writes to `to` each chunk `delay_` after it was read.
  void pump(int from, int to) {
    struct Chunk {
      Clock::time_point due;
      std::string bytes;
    };
    std::mutex mutex;
    std::condition_variable ready;
    std::deque<Chunk> chunks;
    bool closed = false;
    std::thread writer([&] {
      std::unique_lock lock(mutex);
      while (true) {
        ready.wait_for(lock, 50ms, [&] { return !chunks.empty() || closed || stopping_; });
        if (stopping_ || (closed && chunks.empty())) break;
        if (chunks.empty()) continue;
        if (Clock::now() < chunks.front().due) {
          ready.wait_until(lock, chunks.front().due);
          continue;
        }
        Chunk chunk = std::move(chunks.front());
        chunks.pop_front();
        lock.unlock();
        size_t sent = 0;
        while (sent < chunk.bytes.size()) {
          ssize_t n =
              ::send(to, chunk.bytes.data() + sent, chunk.bytes.size() - sent, MSG_NOSIGNAL);
          if (n <= 0) break;
          sent += size_t(n);
        }
        lock.lock();
      }
      ::shutdown(to, SHUT_WR);
    });
    char buffer[65536];
    while (!stopping_) {
      pollfd p{from, POLLIN, 0};
      if (::poll(&p, 1, 50) <= 0) continue;
      ssize_t n = ::recv(from, buffer, sizeof buffer, 0);
      if (n <= 0) break;
      std::lock_guard lock(mutex);
      chunks.push_back({Clock::now() + delay_, std::string(buffer, size_t(n))});
      ready.notify_one();
    }
    {
      std::lock_guard lock(mutex);
      closed = true;
    }
    ready.notify_one();
    writer.join();
  }

  std::string target_ip_;
  int target_port_;
  std::chrono::milliseconds delay_;
  int listen_fd_ = -1, port_ = 0;
  std::atomic<bool> stopping_{false};
  std::thread accept_thread_;
  std::mutex mutex_;
  std::vector<std::thread> pumps_;
  std::vector<int> fds_;
};

// A TCP echo server on `ip` (answers each chunk with the same bytes).
class EchoServer {
 public:
  explicit EchoServer(const std::string& ip) {
    listen_fd_ = listening_socket(ip, &port_);
    thread_ = std::thread([this] {
      std::vector<int> clients;
      while (!stopping_) {
        std::vector<pollfd> polls{{listen_fd_, POLLIN, 0}};
        for (int fd : clients) polls.push_back({fd, POLLIN, 0});
        if (::poll(polls.data(), polls.size(), 50) <= 0) continue;
        if (polls[0].revents & POLLIN) {
          int fd = ::accept4(listen_fd_, nullptr, nullptr, SOCK_CLOEXEC);
          if (fd >= 0) clients.push_back(fd);
        }
        for (size_t i = 1; i < polls.size(); ++i) {
          if (!(polls[i].revents & (POLLIN | POLLHUP))) continue;
          char buffer[4096];
          ssize_t n = ::recv(polls[i].fd, buffer, sizeof buffer, 0);
          if (n > 0) ::send(polls[i].fd, buffer, size_t(n), MSG_NOSIGNAL);
        }
      }
      for (int fd : clients) ::close(fd);
    });
  }
  ~EchoServer() {
    stopping_ = true;
    thread_.join();
    ::close(listen_fd_);
  }
  int port() const { return port_; }

 private:
  int listen_fd_ = -1, port_ = 0;
  std::atomic<bool> stopping_{false};
  std::thread thread_;
};

// Median round trip of one byte over a TCP connection to ip:port, over `rounds` round trips.
inline double median_round_trip_ms(const std::string& ip, int port, int rounds) {
  int fd = connect_to(ip, port);
  if (fd < 0) throw std::runtime_error("cannot connect to " + ip + ":" + std::to_string(port));
  std::vector<double> times;
  for (int i = 0; i < rounds; ++i) {
    auto start = Clock::now();
    char byte = char('a' + i);
    if (::send(fd, &byte, 1, MSG_NOSIGNAL) != 1) break;
    char answer = 0;
    if (::recv(fd, &answer, 1, 0) != 1) break;
    times.push_back(seconds_since(start) * 1000.0);
  }
  ::close(fd);
  if (times.empty()) throw std::runtime_error("no round trip completed");
  std::sort(times.begin(), times.end());
  return times[times.size() / 2];
}

// Sends `count` UDP datagrams to an echo on ip (run from inside a namespace) and returns the
// fraction answered: with loss p each way, about (1 - p)^2.
inline double udp_echo_fraction(NetNamespace& ns, int count) {
  int server = ::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  sockaddr_in address = socket_address(ns.host_ip(), 0);
  socklen_t length = sizeof address;
  ::bind(server, reinterpret_cast<sockaddr*>(&address), sizeof address);
  ::getsockname(server, reinterpret_cast<sockaddr*>(&address), &length);
  int port = ntohs(address.sin_port);
  std::atomic<bool> stop{false};
  std::thread echo([&] {
    while (!stop) {
      pollfd p{server, POLLIN, 0};
      if (::poll(&p, 1, 50) <= 0) continue;
      char buffer[64];
      sockaddr_in from{};
      socklen_t from_length = sizeof from;
      ssize_t n = ::recvfrom(server, buffer, sizeof buffer, 0, reinterpret_cast<sockaddr*>(&from),
                             &from_length);
      if (n > 0)
        ::sendto(server, buffer, size_t(n), 0, reinterpret_cast<sockaddr*>(&from), from_length);
    }
  });
  int answered = 0;
  ns.run_inside([&] {
    int fd = ::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    sockaddr_in target = socket_address(ns.host_ip(), port);
    // Answers are read as they come (a socket buffer full of unread answers would drop some).
    auto drain = [&](int timeout_ms) {
      pollfd p{fd, POLLIN, 0};
      if (::poll(&p, 1, timeout_ms) <= 0) return;
      int value = 0;
      while (::recv(fd, &value, sizeof value, MSG_DONTWAIT) > 0) ++answered;
    };
    for (int i = 0; i < count; ++i) {
      ::sendto(fd, &i, sizeof i, 0, reinterpret_cast<sockaddr*>(&target), sizeof target);
      drain(1);
    }
    auto deadline = Clock::now() + 1s;
    while (Clock::now() < deadline) drain(50);
    ::close(fd);
  });
  stop = true;
  echo.join();
  ::close(server);
  return double(answered) / double(count);
}

}  // namespace penumbra::farm::fault
