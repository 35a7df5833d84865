// The deployment files checked offline by tools/deploy_lint.py: the repository's Dockerfiles,
// compose file, Kubernetes manifests (base and rendered overlays, against the Kubernetes API
// schema of python3-kubernetes) and systemd units pass; broken copies of each are caught with
// the rule that names the problem.
#include <gtest/gtest.h>

#include "tests/deploy/deploy_test_support.h"

namespace penumbra::farm::testing {
namespace {

CommandResult lint(const std::string& arguments) {
  return run_command("/usr/bin/python3 " + shell_quote(source_path("tools/deploy_lint.py")) +
                     " --binary-dir " + shell_quote(PENUMBRA_BINARY_DIR) + " " + arguments);
}

std::string write(const std::filesystem::path& path, const std::string& text) {
  std::filesystem::create_directories(path.parent_path());
  std::ofstream(path) << text;
  return path.string();
}

void expect_problem(const CommandResult& result, const std::string& rule,
                    const std::string& detail) {
  EXPECT_EQ(result.exit_code, 1) << result.output;
  bool found = false;
  std::istringstream lines(result.output);
  for (std::string line; std::getline(lines, line);)
    found = found || (line.find(": " + rule + ": ") != std::string::npos &&
                      line.find(detail) != std::string::npos);
  EXPECT_TRUE(found) << "expected " << rule << " about '" << detail << "' in:\n" << result.output;
}

TEST(DeployLint, RepositoryFilesPass) {
  for (const char* what : {"docker", "compose", "k8s", "systemd"}) {
    CommandResult result = lint(what);
    EXPECT_EQ(result.exit_code, 0) << what << ":\n" << result.output;
    EXPECT_NE(result.output.find(", 0 problems"), std::string::npos) << result.output;
  }
}

TEST(DeployLint, OverlaysRenderWithTheirPatches) {
  CommandResult production =
      lint("--render " + shell_quote(source_path("deploy/k8s/overlays/production")) + " all");
  ASSERT_EQ(production.exit_code, 0) << production.output;
  EXPECT_NE(production.output.find("--tls-client-ca"), std::string::npos);
  EXPECT_NE(production.output.find("type: External"), std::string::npos);
  EXPECT_NE(production.output.find("image: penumbra/worker:0.1.0"), std::string::npos);
  EXPECT_NE(production.output.find("namespace: penumbra"), std::string::npos);
  EXPECT_EQ(production.output.find("grpc:\n            port"), std::string::npos)
      << "the production probes replace gRPC by HTTP";
  CommandResult dev =
      lint("--render " + shell_quote(source_path("deploy/k8s/overlays/dev")) + " all");
  ASSERT_EQ(dev.exit_code, 0) << dev.output;
  EXPECT_NE(dev.output.find("storage: 2Gi"), std::string::npos);
  EXPECT_EQ(dev.output.find("storage: 20Gi"), std::string::npos);
}

TEST(DeployLint, BrokenDockerfileIsCaught) {
  auto dir = fresh_directory("lint-docker");
  std::string dockerfile = write(dir / "bad.Dockerfile", R"(FROM debian:latest AS build
RUN apt-get update
RUN apt-get install -y build-essential
COPY no-such-folder /src/
FROM ubuntu
RUN apt-get update && apt-get install -y libgrpc++-dev
COPY --from=builder /src/build/server/penumbra-coordinator /usr/local/bin/penumbra-coordinator
EXPOSE 8080
ENTRYPOINT /usr/local/bin/penumbra-coordinator --listen 0.0.0.0:7420 --no-such-flag
)");
  CommandResult result = lint("docker --dockerfile " + shell_quote(dockerfile));
  expect_problem(result, "DF-FROM", "debian:latest uses latest");
  expect_problem(result, "DF-FROM", "ubuntu has no tag");
  expect_problem(result, "DF-APT", "apt-get update without an install");
  expect_problem(result, "DF-APT", "without --no-install-recommends");
  expect_problem(result, "DF-APT", "rm -rf /var/lib/apt/lists");
  expect_problem(result, "DF-APT", "libgrpc++-dev: a -dev package at run time");
  expect_problem(result, "DF-COPY", "no-such-folder does not exist");
  expect_problem(result, "DF-COPY", "--from=builder names no stage");
  expect_problem(result, "DF-USER", "no USER");
  expect_problem(result, "DF-HEALTH", "no HEALTHCHECK");
  expect_problem(result, "DF-CMD", "ENTRYPOINT in shell form");
  expect_problem(result, "DF-CMD", "has no flag --no-such-flag");
  expect_problem(result, "DF-PORT", "EXPOSE [8080]");
  expect_problem(result, "DF-LIBS", "not installed");
  std::filesystem::remove_all(dir);
}

TEST(DeployLint, BrokenComposeIsCaught) {
  auto dir = fresh_directory("lint-compose");
  std::string compose = write(dir / "compose.yaml", R"(services:
  coordinator:
    image: penumbra/coordinator:latest
    command: ["--listen", "0.0.0.0:7420", "--data-dir", "/data", "--http-listen", "0.0.0.0:9090"]
    volumes: ["other:/elsewhere"]
  worker:
    image: penumbra/worker:0.1.0
    environment:
      PENUMBRA_COORDINATOR: coordinatr:7420
    deploy:
      replicas: 2
)");
  CommandResult result = lint("compose --compose " + shell_quote(compose));
  expect_problem(result, "CO-IMAGE", "is not pinned");
  expect_problem(result, "CO-VOLUME", "--data-dir /data is not on a volume");
  expect_problem(result, "CO-SERVICES", "2 workers, expected 3");
  expect_problem(result, "CO-ADDRESS", "coordinatr:7420");
  expect_problem(result, "CO-HEALTH", "/healthz");
  std::filesystem::remove_all(dir);
}

TEST(DeployLint, SchemaViolationsAreCaught) {
  auto dir = fresh_directory("lint-k8s");
  std::string manifest = write(dir / "bad.yaml", R"(apiVersion: apps/v1
kind: StatefulSet
metadata:
  name: bad
spec:
  replicas: "1"
  serviceName: x
  selector: {matchLabels: {app: bad}}
  template:
    metadata: {labels: {app: bad}}
    spec:
      containers:
        - image: penumbra/coordinator:0.1.0
          livenessProbe:
            grpc: {service: ""}
          ports: [{containerPort: "7420"}]
          resourcez: {}
---
apiVersion: autoscaling/v2
kind: HorizontalPodAutoscaler
metadata: {name: hpa}
spec:
  maxReplicas: 3
---
apiVersion: v1
kind: Service
metadata: {name: s}
spec:
  ports: 7420
)");
  CommandResult result = lint("k8s --manifest " + shell_quote(manifest));
  expect_problem(result, "K8S-SCHEMA", "spec.replicas: expected an integer");
  expect_problem(result, "K8S-SCHEMA", "livenessProbe.grpc.port: required field missing");
  expect_problem(result, "K8S-SCHEMA", "resourcez: unknown field");
  expect_problem(result, "K8S-SCHEMA", "containerPort: expected an integer");
  expect_problem(result, "K8S-SCHEMA", "`name`, must not be `None`");
  expect_problem(result, "K8S-SCHEMA", "`scale_target_ref`, must not be `None`");
  expect_problem(result, "K8S-SCHEMA", "spec.ports: expected a list");
  std::filesystem::remove_all(dir);
}

TEST(DeployLint, BrokenUnitIsCaught) {
  auto dir = fresh_directory("lint-systemd");
  std::string unit = write(dir / "penumbra-worker@.service", R"([Unit]
Description=bad worker
[Service]
ExecStart=/usr/local/bin/penumbra-worker --coordinator 10.0.0.1:7420 --cache-dir /srv/cache --thread 2
Restart=sometimes
ProtectSystem=full
[Install]
WantedBy=multi-user.target
)");
  CommandResult result = lint("systemd --unit " + shell_quote(unit));
  expect_problem(result, "SD-FLAG", "has no flag --thread");
  expect_problem(result, "SD-HARDEN", "NoNewPrivileges=yes missing");
  expect_problem(result, "SD-HARDEN", "ProtectSystem=strict missing");
  expect_problem(result, "SD-HARDEN", "neither DynamicUser=yes nor a non-root User=");
  expect_problem(result, "SD-HARDEN", "--cache-dir /srv/cache");
  if (std::filesystem::exists("/usr/bin/systemd-analyze"))
    expect_problem(result, "SD-VERIFY", "restart specifier");
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace penumbra::farm::testing
