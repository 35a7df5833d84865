// The coordinator listens on loopback unless told otherwise: started without --listen it serves
// 127.0.0.1:7420 (read back from the kernel's socket table, /proc/<pid>/net/tcp and tcp6) and a
// client reaches it on 127.0.0.1. Run in a fresh network namespace (unshare --net, as root) so
// port 7420 is free whatever else runs on the machine; without that, on the host when 7420 is
// free, else skipped. A coordinator told --listen 0.0.0.0:0 shows as a wildcard listener, which
// checks the socket-table reading itself.
#if __has_include("penumbra/v1/farm.pb.h")
#include <gtest/gtest.h>

#include <algorithm>
#include <set>

#include "security_test_support.h"

namespace penumbra::farm {
namespace {

using namespace std::chrono_literals;
using testing::ChildProcess;

// A local address of /proc/net/tcp or tcp6 (hex of 32-bit words in host order, little-endian
// here) as text: "127.0.0.1", "0.0.0.0", "::"; an IPv4-mapped IPv6 address (gRPC binds IPv4
// addresses through IPv6 sockets) as its IPv4 address.
std::string address_text(const std::string& hex) {
  std::vector<int> bytes;
  for (size_t word = 0; word + 8 <= hex.size(); word += 8) {
    uint32_t value = uint32_t(std::stoul(hex.substr(word, 8), nullptr, 16));
    for (int shift = 0; shift < 32; shift += 8) bytes.push_back(int((value >> shift) & 0xff));
  }
  auto dotted = [&](size_t first) {
    return std::to_string(bytes[first]) + "." + std::to_string(bytes[first + 1]) + "." +
           std::to_string(bytes[first + 2]) + "." + std::to_string(bytes[first + 3]);
  };
  if (bytes.size() == 4) return dotted(0);
  if (bytes.size() != 16) return "?" + hex;
  bool zero_prefix = std::all_of(bytes.begin(), bytes.begin() + 10, [](int b) { return b == 0; });
  if (zero_prefix && bytes[10] == 0xff && bytes[11] == 0xff) return dotted(12);
  if (std::all_of(bytes.begin(), bytes.end(), [](int b) { return b == 0; })) return "::";
  return "ipv6:" + hex;
}

// Local addresses (as address_text) of the TCP sockets listening on `port` in the network
// namespace of process `pid`, from /proc/<pid>/net/tcp and tcp6.
std::set<std::string> listening_addresses(int pid, int port) {
  std::set<std::string> addresses;
  char port_hex[8];
  std::snprintf(port_hex, sizeof port_hex, "%04X", port);
  for (const char* table : {"tcp", "tcp6"}) {
    std::ifstream in("/proc/" + std::to_string(pid) + "/net/" + table);
    std::string line;
    std::getline(in, line);  // header
    while (std::getline(in, line)) {
      std::istringstream fields(line);
      std::string slot, local, remote, state;
      fields >> slot >> local >> remote >> state;
      size_t colon = local.find(':');
      if (state == "0A" && colon != std::string::npos && local.substr(colon + 1) == port_hex)
        addresses.insert(address_text(local.substr(0, colon)));
    }
  }
  return addresses;
}

bool port_free_on_host(int port) {
  for (in_addr_t host : {htonl(INADDR_LOOPBACK), htonl(INADDR_ANY)}) {
    int fd = ::socket(AF_INET, SOCK_STREAM, 0);
    int one = 1;
    ::setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
    sockaddr_in address{};
    address.sin_family = AF_INET;
    address.sin_addr.s_addr = host;
    address.sin_port = htons(uint16_t(port));
    bool ok = ::bind(fd, reinterpret_cast<sockaddr*>(&address), sizeof address) == 0;
    ::close(fd);
    if (!ok) return false;
  }
  return true;
}

std::string read_text(const std::filesystem::path& path) {
  std::ifstream in(path);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

// Starts `coordinator_arguments` through /bin/sh (optionally inside `unshare --net` with
// loopback up); the shell writes its pid, which the coordinator keeps by exec.
struct WrappedCoordinator {
  std::unique_ptr<ChildProcess> process;
  int pid = 0;
  int port = 0;
};

std::optional<WrappedCoordinator> start_wrapped(const std::filesystem::path& dir,
                                                const std::string& coordinator_arguments,
                                                bool isolated) {
  auto pid_file = dir / "pid";
  auto port_file = dir / "port";
  std::filesystem::remove(pid_file);
  std::filesystem::remove(port_file);
  std::string script = std::string(isolated ? "ip link set lo up && " : "") + "echo $$ > '" +
                       pid_file.string() + "' && exec '" +
                       testing::binary("server/penumbra-coordinator") + "' --data-dir '" +
                       (dir / "data").string() + "' --port-file '" + port_file.string() + "' " +
                       coordinator_arguments;
  std::vector<std::string> command = {"/bin/sh", "-c", script};
  if (isolated) command.insert(command.begin(), {"/usr/bin/unshare", "--net"});
  WrappedCoordinator started;
  started.process = std::make_unique<ChildProcess>(command, (dir / "coordinator.log").string());
  auto deadline = std::chrono::steady_clock::now() + 20s;
  while (!std::filesystem::exists(port_file)) {
    if (!started.process->running() || std::chrono::steady_clock::now() > deadline)
      return std::nullopt;
    std::this_thread::sleep_for(20ms);
  }
  std::ifstream(pid_file) >> started.pid;
  std::ifstream(port_file) >> started.port;
  return started;
}

TEST(FarmListen, DefaultIsLoopbackOnly) {
  auto dir = testing::fresh_directory("listen");
  bool isolated = ::geteuid() == 0 && std::filesystem::exists("/usr/bin/unshare") &&
                  std::filesystem::exists("/usr/bin/nsenter");
  std::optional<WrappedCoordinator> coordinator;
  if (isolated) coordinator = start_wrapped(dir, "", true);
  if (!coordinator) {
    isolated = false;
    if (!port_free_on_host(7420))
      GTEST_SKIP() << "no network namespace (not root or no unshare) and port 7420 is taken";
    coordinator = start_wrapped(dir, "", false);
  }
  ASSERT_TRUE(coordinator) << read_text(dir / "coordinator.log");
  EXPECT_EQ(coordinator->port, 7420);
  // 127.0.0.1 only: no wildcard (0.0.0.0 or ::) and no other address.
  EXPECT_EQ(listening_addresses(coordinator->pid, 7420), std::set<std::string>{"127.0.0.1"});

  // A client reaches it on 127.0.0.1.
  if (isolated) {
    auto log = dir / "client.log";
    ChildProcess client(
        {"/usr/bin/nsenter", "--net=/proc/" + std::to_string(coordinator->pid) + "/ns/net",
         testing::binary("client/penumbra"), "list", "--coordinator", "127.0.0.1:7420"},
        log.string());
    EXPECT_EQ(client.wait_exit(60s), 0) << read_text(log);
    EXPECT_NE(read_text(log).find("JOB"), std::string::npos) << read_text(log);
  } else {
    FarmClient client("127.0.0.1:7420");
    EXPECT_TRUE(client.list().empty());
  }
}

TEST(FarmListen, ToldOtherwiseItListensWhereTold) {
  auto dir = testing::fresh_directory("listen-any");
  auto coordinator = start_wrapped(dir, "--listen 0.0.0.0:0", false);
  ASSERT_TRUE(coordinator) << read_text(dir / "coordinator.log");
  // A wildcard: gRPC binds 0.0.0.0 as a dual-stack "::" socket.
  std::set<std::string> addresses = listening_addresses(coordinator->pid, coordinator->port);
  EXPECT_TRUE(addresses == std::set<std::string>{"::"} ||
              addresses == std::set<std::string>{"0.0.0.0"})
      << ::testing::PrintToString(addresses);
  FarmClient client("127.0.0.1:" + std::to_string(coordinator->port));
  EXPECT_TRUE(client.list().empty());
}

}  // namespace
}  // namespace penumbra::farm
#else
#include <gtest/gtest.h>
TEST(FarmNotBuilt, Skipped) {
  GTEST_SKIP() << "configured with PENUMBRA_FARM=OFF";
}
#endif
