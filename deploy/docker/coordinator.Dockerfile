# penumbra-coordinator image. Build from the repository root:
#   docker build -f deploy/docker/coordinator.Dockerfile -t penumbra/coordinator:0.1.0 .
# Checked by tools/deploy_lint.py (tests/deploy/deploy_lint_test.cpp): pinned base tags, non-root
# user, health check, apt lists cleaned, COPY sources, binaries, flags and ports.

FROM debian:12.8 AS build
WORKDIR /src
COPY tools/setup.sh tools/setup.sh
RUN bash tools/setup.sh && rm -rf /var/lib/apt/lists/*
COPY CMakeLists.txt ./
COPY core core
COPY proto proto
COPY server server
COPY worker worker
COPY client client
COPY tools tools
COPY scenes scenes
RUN cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release -DPENUMBRA_FARM=ON \
      -DPENUMBRA_TESTS=OFF -DPENUMBRA_BENCH=OFF \
    && ninja -C build penumbra-coordinator penumbra penumbra_oiio

FROM debian:12.8
# Only the shared libraries the binaries load (their DT_NEEDED packages), curl for the health
# check, and CA certificates.
RUN apt-get update \
    && apt-get install -y --no-install-recommends \
       libabsl20220623 libembree3-3 libfmt9 libgrpc++1.51 libgrpc29 libopenimageio2.4 \
       libprotobuf32 libspdlog1.10 libsqlite3-0 libssl3 libtbb12 libtinyobjloader2rc10 \
       libcpp-httplib0.11 libplplotcxx15 libpolyclipping22 zlib1g curl ca-certificates \
    && rm -rf /var/lib/apt/lists/*
RUN groupadd --system --gid 10001 penumbra \
    && useradd --system --uid 10001 --gid penumbra --home-dir /var/lib/penumbra \
       --shell /usr/sbin/nologin penumbra \
    && install -d -o penumbra -g penumbra -m 0750 /var/lib/penumbra
COPY --from=build /src/build/server/penumbra-coordinator /usr/local/bin/penumbra-coordinator
COPY --from=build /src/build/client/penumbra /usr/local/bin/penumbra
COPY --from=build /src/build/lib/libpenumbra_oiio.so /usr/local/lib/penumbra/libpenumbra_oiio.so
USER penumbra
WORKDIR /var/lib/penumbra
VOLUME ["/var/lib/penumbra"]
# 7420: gRPC (jobs and workers APIs, grpc.health.v1); 9090: HTTP (metrics, /healthz, dashboard).
EXPOSE 7420 9090
HEALTHCHECK --interval=15s --timeout=3s --start-period=20s --retries=3 \
  CMD curl -fsS http://127.0.0.1:9090/healthz || exit 1
ENTRYPOINT ["/usr/local/bin/penumbra-coordinator"]
CMD ["--listen", "0.0.0.0:7420", "--data-dir", "/var/lib/penumbra", "--http-listen", "0.0.0.0:9090"]
