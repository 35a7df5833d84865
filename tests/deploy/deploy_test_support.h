#pragma once
// Helpers for the deploy tests: HTTP GETs against the coordinator's HTTP frontend, commands run
// with their output captured, and Prometheus text parsed by the reference parser
// (python3-prometheus-client's text_string_to_metric_families, via tests/deploy/parse_metrics.py).

#include <httplib.h>
#include <sys/wait.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "tests/farm/farm_test_support.h"

namespace penumbra::farm::testing {

inline std::string source_path(const std::string& relative) {
  return std::string(PENUMBRA_SOURCE_DIR) + "/" + relative;
}

struct HttpReply {
  int status = 0;  // 0: no answer
  std::string body;
  std::string content_type;
  std::map<std::string, std::string> headers;
};

inline HttpReply http_get(const std::string& host, int port, const std::string& path) {
  httplib::Client client(host, port);
  client.set_connection_timeout(std::chrono::seconds(5));
  client.set_read_timeout(std::chrono::seconds(20));
  HttpReply reply;
  if (auto result = client.Get(path)) {
    reply.status = result->status;
    reply.body = result->body;
    reply.content_type = result->get_header_value("Content-Type");
    for (const auto& [key, value] : result->headers) reply.headers[key] = value;
  }
  return reply;
}

// Polls GET /healthz until it answers 200 (throws after `timeout`).
inline void wait_healthy(const std::string& host, int port,
                         std::chrono::milliseconds timeout = std::chrono::seconds(20)) {
  auto deadline = std::chrono::steady_clock::now() + timeout;
  while (http_get(host, port, "/healthz").status != 200) {
    if (std::chrono::steady_clock::now() > deadline)
      throw std::runtime_error("no /healthz on " + host + ":" + std::to_string(port));
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
}

struct CommandResult {
  int exit_code = -1;
  std::string output;  // stdout and stderr
};

// Runs `command` through /bin/sh with stderr folded into stdout.
inline CommandResult run_command(const std::string& command) {
  CommandResult result;
  FILE* pipe = ::popen((command + " 2>&1").c_str(), "r");
  if (!pipe) throw std::runtime_error("popen failed: " + command);
  char buffer[4096];
  size_t n;
  while ((n = std::fread(buffer, 1, sizeof buffer, pipe)) > 0) result.output.append(buffer, n);
  int status = ::pclose(pipe);
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return result;
}

inline std::string shell_quote(const std::string& text) {
  std::string out = "'";
  for (char c : text) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

// One sample of a scrape, as the Prometheus parser saw it.
struct MetricSample {
  std::string family, type, name;
  std::map<std::string, std::string> labels;
  double value = 0;
};

struct Scrape {
  std::vector<MetricSample> samples;
  std::map<std::string, std::string> family_types;  // family name -> counter, gauge, ...

  // The value of the sample `name` whose labels include `labels`; throws when there is none.
  double value(const std::string& name,
               const std::map<std::string, std::string>& labels = {}) const {
    for (const MetricSample& sample : samples) {
      if (sample.name != name) continue;
      bool match = true;
      for (const auto& [key, value] : labels) {
        auto it = sample.labels.find(key);
        match = match && it != sample.labels.end() && it->second == value;
      }
      if (match) return sample.value;
    }
    throw std::runtime_error("no sample " + name);
  }
};

// Parses Prometheus text with python3-prometheus-client; throws with the parser's message when
// it rejects the text.
inline Scrape parse_prometheus(const std::string& text, const std::filesystem::path& scratch) {
  auto input = scratch / "scrape.txt";
  std::ofstream(input, std::ios::binary) << text;
  CommandResult parsed =
      run_command("/usr/bin/python3 " + shell_quote(source_path("tests/deploy/parse_metrics.py")) +
                  " " + shell_quote(input.string()));
  if (parsed.exit_code != 0) throw std::runtime_error("metrics parser: " + parsed.output);
  // Lines: family TAB type TAB sample TAB value TAB key=value (TAB-separated, repeated).
  Scrape scrape;
  std::istringstream lines(parsed.output);
  std::string line;
  while (std::getline(lines, line)) {
    std::vector<std::string> fields;
    std::istringstream parts(line);
    std::string field;
    while (std::getline(parts, field, '\t')) fields.push_back(field);
    if (fields.size() < 4) throw std::runtime_error("metrics parser printed: " + line);
    MetricSample sample{fields[0], fields[1], fields[2], {}, std::stod(fields[3])};
    for (size_t i = 4; i < fields.size(); ++i) {
      size_t equals = fields[i].find('=');
      sample.labels[fields[i].substr(0, equals)] = fields[i].substr(equals + 1);
    }
    scrape.family_types[sample.family] = sample.type;
    scrape.samples.push_back(std::move(sample));
  }
  return scrape;
}

// A coordinator process serving HTTP on loopback (a port that was free a moment ago), with
// further coordinator arguments (e.g. --tokens-file) in `extra`.
struct HttpCoordinator {
  explicit HttpCoordinator(const std::filesystem::path& data_dir, double lease_seconds = 2.0,
                           std::vector<std::string> extra = {})
      : http_port(free_port()), process(data_dir, 0, with_http(http_port, extra), lease_seconds) {
    wait_healthy("127.0.0.1", http_port);
  }
  static std::vector<std::string> with_http(int port, std::vector<std::string> extra) {
    extra.insert(extra.begin(), {"--http-listen", "127.0.0.1:" + std::to_string(port)});
    return extra;
  }
  HttpReply get(const std::string& path) const { return http_get("127.0.0.1", http_port, path); }
  std::string url(const std::string& path = "/") const {
    return "http://127.0.0.1:" + std::to_string(http_port) + path;
  }
  int http_port;
  CoordinatorProcess process;
};

}  // namespace penumbra::farm::testing
