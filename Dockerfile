# syntax=docker/dockerfile:1
# bsdflab on Debian bookworm, in stages:
#   build    compiles the wheel (C++ core included) with the build tools and Embree headers
#   runtime  (the default) installs that wheel with only its runtime libraries and runs
#            `bsdflab serve` as a non-root user, the job store and artefacts on a volume
#   dev      the source tree set up by ./dev.sh, exactly as on a fresh machine (tests)
#
#   docker build -t bsdflab .
#   docker run --rm -p 8000:8000 -v bsdflab-data:/data bsdflab          # http://localhost:8000
#   docker run --rm -v "$PWD/out:/out" bsdflab render snake --out /out/snake.exr
#   docker build --target dev -t bsdflab-dev . && docker run --rm --entrypoint ./dev.sh bsdflab-dev test
ARG PYTHON_IMAGE=python:3.11-slim-bookworm

FROM ${PYTHON_IMAGE} AS build
# libembree-dev: the renderer's ray intersection (headers, CMake config, TBB). CMake, Ninja,
# scikit-build-core and pybind11 come from PyPI into pip's isolated build environment.
RUN apt-get update -qq \
 && apt-get install -y -qq --no-install-recommends build-essential libembree-dev \
 && rm -rf /var/lib/apt/lists/*
WORKDIR /src
COPY . .
RUN pip wheel --no-cache-dir --no-deps --wheel-dir /wheels .

FROM ${PYTHON_IMAGE} AS dev
WORKDIR /bsdflab
COPY . .
RUN ./dev.sh setup && rm -rf /var/lib/apt/lists/* /root/.cache/pip
ENTRYPOINT ["/bsdflab/.venv/bin/bsdflab"]
CMD ["--help"]

FROM ${PYTHON_IMAGE} AS runtime
# Runtime libraries of the C++ core: Embree 3 (it brings TBB). Mitsuba's LLVM variants
# (reference cross-checks, not the service) would also need libllvm19.
RUN apt-get update -qq \
 && apt-get install -y -qq --no-install-recommends libembree3-3 \
 && rm -rf /var/lib/apt/lists/*
COPY --from=build /wheels /wheels
RUN python -m venv /opt/bsdflab \
 && wheel=$(ls /wheels/bsdflab-*.whl) \
 && /opt/bsdflab/bin/pip install --no-cache-dir "${wheel}[service,dask]" \
 && rm -rf /wheels
RUN useradd --system --uid 10001 --create-home --home-dir /home/bsdflab bsdflab \
 && mkdir -p /data && chown bsdflab:bsdflab /data
ENV PATH=/opt/bsdflab/bin:$PATH \
    BSDFLAB_DATA_DIR=/data \
    BSDFLAB_HOST=0.0.0.0 \
    BSDFLAB_PORT=8000 \
    PYTHONUNBUFFERED=1
VOLUME ["/data"]
EXPOSE 8000
USER bsdflab
WORKDIR /home/bsdflab
HEALTHCHECK --interval=30s --timeout=5s --start-period=30s \
  CMD python -c "import urllib.request; urllib.request.urlopen('http://127.0.0.1:${BSDFLAB_PORT}/healthz', timeout=4)"
ENTRYPOINT ["bsdflab"]
CMD ["serve", "--host", "0.0.0.0"]
