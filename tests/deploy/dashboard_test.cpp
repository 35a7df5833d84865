// The dashboard in headless Chromium against a real coordinator with tokens and a worker, opened
// as a browser user would (a viewer token in the address: the script sends it to the JSON API as
// a header): the jobs are listed, a running job's progress moves between two DOM dumps, its
// MRSE-against-time chart is drawn (an SVG path through the curve's points), the workers are
// listed; with PENUMBRA_TEST_SCREENSHOTS set, a screenshot is saved too.
#include <gtest/gtest.h>

#include <cstdlib>
#include <regex>

#include "tests/deploy/deploy_test_support.h"

namespace penumbra::farm::testing {
namespace {

const char* kChromium = "/usr/bin/chromium";

// The DOM after the page's script ran for a while (virtual time lets its timers fire; the
// fetches are real).
std::string dump_dom(const std::string& url, const std::filesystem::path& profile) {
  CommandResult result = run_command(
      std::string("timeout 60 ") + kChromium +
      " --headless=new --no-sandbox --disable-gpu --disable-dev-shm-usage --no-first-run"
      " --user-data-dir=" +
      shell_quote(profile.string()) + " --virtual-time-budget=2500 --dump-dom " + shell_quote(url));
  if (result.output.find("</html>") == std::string::npos)
    throw std::runtime_error("chromium printed no DOM (exit " + std::to_string(result.exit_code) +
                             "): " + result.output.substr(0, 2000));
  return result.output;
}

// Attribute `name` of the first element whose opening tag matches `tag_pattern` and has
// `key_attribute`="key_value"; empty when none.
std::string attribute(const std::string& dom, const std::string& key_attribute,
                      const std::string& key_value, const std::string& name) {
  std::regex tag("<[a-z]+[^>]*" + key_attribute + "=\"" + key_value + "\"[^>]*>");
  std::smatch match;
  if (!std::regex_search(dom, match, tag)) return "";
  std::regex value(" " + name + "=\"([^\"]*)\"");
  std::smatch found;
  std::string text = match.str();
  return std::regex_search(text, found, value) ? found[1].str() : "";
}

int count(const std::string& dom, const std::string& needle) {
  int n = 0;
  for (size_t at = dom.find(needle); at != std::string::npos; at = dom.find(needle, at + 1)) ++n;
  return n;
}

TEST(Dashboard, ChromiumShowsJobsProgressChartAndWorkers) {
  if (!std::filesystem::exists(kChromium)) GTEST_SKIP() << "no " << kChromium;
  auto dir = fresh_directory("dashboard");
  const std::string client_token = "client-dash-0123456789abcdef";
  const std::string worker_token = "worker-dash-0123456789abcdef";
  const std::string viewer_token = "viewer-dash-0123456789abcdef";
  std::filesystem::create_directories(dir);
  std::ofstream(dir / "tokens.txt") << "client dash " << client_token << "\nworker w "
                                    << worker_token << "\nviewer wall " << viewer_token << "\n";
  HttpCoordinator coordinator(dir / "coordinator", 2.0,
                              {"--tokens-file", (dir / "tokens.txt").string()});
  FarmConnection connection;
  connection.address = coordinator.process.address();
  connection.token = client_token;
  FarmClient client(connection);
  std::string scene = write_scene(dir, 96, 64);

  // A reference, then a long job scored against it (one pass per task: the curve grows fast).
  std::string reference = client.submit(job_spec(scene, "sa", 8, 3, 32, 8)).job_id();
  v1::JobSpec spec = job_spec(scene, "area", 1, 11, 32, 1);
  spec.set_compute_seconds(120);  // opens one pass block at a time; cancelled at the end
  spec.set_reference_job(reference);
  spec.set_name("dashboard-job");
  std::string job = client.submit(spec).job_id();
  auto worker = start_worker_with(coordinator.process.address(), dir, "dash-worker",
                                  {"--token", worker_token});
  wait_until(client, job, [](const v1::JobStatus& s) { return s.curve_size() >= 2; });

  // Without a token the page is refused.
  EXPECT_EQ(coordinator.get("/").status, 401);
  const std::string url = coordinator.url("/?token=" + viewer_token);
  std::string first = dump_dom(url, dir / "profile");
  std::string second = dump_dom(url, dir / "profile");

  // Jobs listed (both), the running one with its state.
  EXPECT_EQ(count(second, "class=\"job"), 2) << second.substr(0, 4000);
  EXPECT_NE(attribute(second, "data-job-id", reference, "data-state"), "");
  EXPECT_EQ(attribute(second, "data-job-id", job, "data-state"), "running");
  // Progress moved between the dumps.
  std::string passes_before = attribute(first, "data-job-id", job, "data-passes");
  std::string passes_after = attribute(second, "data-job-id", job, "data-passes");
  ASSERT_FALSE(passes_before.empty()) << first.substr(0, 4000);
  ASSERT_FALSE(passes_after.empty());
  EXPECT_GT(std::stoi(passes_after), std::stoi(passes_before));
  // The chart: a path with at least two points (M x y L x y ...), and the point count.
  std::regex curve("<path[^>]*class=\"curve\"[^>]*>");
  std::smatch path;
  ASSERT_TRUE(std::regex_search(second, path, curve)) << second.substr(0, 4000);
  std::string path_tag = path.str();
  EXPECT_TRUE(std::regex_search(path_tag, std::regex(" d=\"M[-0-9. ]+( L[-0-9. ]+)+\"")))
      << path_tag;
  std::smatch points;
  ASSERT_TRUE(std::regex_search(path_tag, points, std::regex("data-points=\"([0-9]+)\"")));
  EXPECT_GE(std::stoi(points[1].str()), 2);
  // The workers table and the live preview of the selected (running) job.
  EXPECT_EQ(attribute(second, "class", "worker", "data-alive"), "true");
  EXPECT_NE(second.find("/api/jobs/" + job + "/preview.png"), std::string::npos);
  EXPECT_EQ(attribute(second, "id", "updated", "id"), "updated");
  EXPECT_EQ(second.find("id=\"error\">Error"), std::string::npos);

  // A screenshot for people (kept in the build folder), when asked for: a third Chromium start
  // costs 10-30 s of the test command and checks nothing the two DOM dumps do not.
  if (std::getenv("PENUMBRA_TEST_SCREENSHOTS") != nullptr) {
    auto screenshot = std::filesystem::path(PENUMBRA_BINARY_DIR) / "deploy-dashboard.png";
    std::filesystem::remove(screenshot);
    run_command(std::string("timeout 60 ") + kChromium +
                " --headless=new --no-sandbox --disable-gpu --disable-dev-shm-usage --no-first-run"
                " --hide-scrollbars --user-data-dir=" +
                shell_quote((dir / "profile").string()) +
                " --window-size=1200,900 --virtual-time-budget=2000 --screenshot=" +
                shell_quote(screenshot.string()) + " " + shell_quote(url));
    // Best effort: on a heavily loaded machine Chromium's screenshot can outlast its 60 s timeout;
    // the checks above (two DOM dumps) are the test.
    if (std::filesystem::exists(screenshot))
      EXPECT_GT(std::filesystem::file_size(screenshot), 10'000u);
    else
      std::printf("no dashboard screenshot: Chromium did not finish within 60 s\n");
  }

  client.cancel(job);
  worker->signal(SIGTERM);
  worker->wait_exit(std::chrono::seconds(30));
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace penumbra::farm::testing
