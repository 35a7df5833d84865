# penumbra-worker image. Build from the repository root:
#   docker build -f deploy/docker/worker.Dockerfile -t penumbra/worker:0.1.0 .
# The coordinator's address comes from PENUMBRA_COORDINATOR (host:port) or --coordinator.
# Checked by tools/deploy_lint.py (tests/deploy/deploy_lint_test.cpp).

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
    && ninja -C build penumbra-worker penumbra_oiio

FROM debian:12.8
RUN apt-get update \
    && apt-get install -y --no-install-recommends \
       libabsl20220623 libembree3-3 libfmt9 libgrpc++1.51 libgrpc29 libopenimageio2.4 \
       libprotobuf32 libspdlog1.10 libssl3 libtbb12 libtinyobjloader2rc10 ca-certificates \
    && rm -rf /var/lib/apt/lists/*
RUN groupadd --system --gid 10001 penumbra \
    && useradd --system --uid 10001 --gid penumbra --home-dir /var/cache/penumbra \
       --shell /usr/sbin/nologin penumbra \
    && install -d -o penumbra -g penumbra -m 0750 /var/cache/penumbra
COPY --from=build /src/build/worker/penumbra-worker /usr/local/bin/penumbra-worker
COPY --from=build /src/build/lib/libpenumbra_oiio.so /usr/local/lib/penumbra/libpenumbra_oiio.so
USER penumbra
WORKDIR /var/cache/penumbra
ENV PENUMBRA_COORDINATOR=coordinator:7420
# The worker serves no port: it is healthy while it can reach its coordinator's gRPC port
# (a TCP connect from bash, no extra tool). SIGTERM drains it (finishes the tasks it holds).
HEALTHCHECK --interval=30s --timeout=5s --start-period=10s --retries=3 \
  CMD ["bash", "-c", "exec 3<>/dev/tcp/${PENUMBRA_COORDINATOR%:*}/${PENUMBRA_COORDINATOR##*:}"]
STOPSIGNAL SIGTERM
ENTRYPOINT ["/usr/local/bin/penumbra-worker"]
CMD ["--cache-dir", "/var/cache/penumbra"]
