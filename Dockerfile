# bsdflab on Debian bookworm, set up exactly as on a fresh machine: ./dev.sh setup installs
# the system packages (build tools, libembree-dev, libllvm19), a venv and the package.
#   docker build -t bsdflab .
#   docker run --rm -v "$PWD/out:/bsdflab/out" bsdflab render snake --out out/snake.exr
#   docker run --rm --entrypoint ./dev.sh bsdflab test
FROM python:3.11-slim-bookworm

WORKDIR /bsdflab
COPY . .
RUN ./dev.sh setup && rm -rf /var/lib/apt/lists/* /root/.cache/pip

ENTRYPOINT ["/bsdflab/.venv/bin/bsdflab"]
CMD ["--help"]
