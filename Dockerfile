# stickslip in a container: a release build, then a slim runtime with the
# Vulkan loader and Mesa's lavapipe (so the image also runs on CPU-only
# nodes; on NVIDIA nodes the container toolkit mounts the driver's Vulkan ICD
# and wgpu takes the hardware GPU first).
#
#   docker build -t stickslip:latest .
#   docker run --rm stickslip:latest check-gpu --allow-software-gpu   # the driver preflight
#   docker run --rm -v "$PWD/out:/out" stickslip:latest sweep --out /out/sweep
#
# deploy/kubernetes and deploy/slurm use this image as `stickslip:latest`
# (Kubernetes: imagePullPolicy IfNotPresent, so a locally built or
# side-loaded image is used without a registry).

FROM rust:1-bookworm AS build
WORKDIR /src
COPY . .
RUN cargo build --release --locked --bin stickslip \
    && install -D target/release/stickslip /out/usr/local/bin/stickslip \
    && /out/usr/local/bin/stickslip completions bash > stickslip.bash \
    && install -D -m 644 stickslip.bash /out/usr/share/bash-completion/completions/stickslip \
    && /out/usr/local/bin/stickslip man > stickslip.1 \
    && install -D -m 644 stickslip.1 /out/usr/share/man/man1/stickslip.1

FROM debian:bookworm-slim
RUN apt-get update \
    && apt-get install -y --no-install-recommends libvulkan1 mesa-vulkan-drivers \
    && rm -rf /var/lib/apt/lists/*
COPY --from=build /out/ /
# NVIDIA container toolkit: "graphics" mounts the driver's Vulkan ICD.
ENV NVIDIA_DRIVER_CAPABILITIES=compute,utility,graphics \
    XDG_RUNTIME_DIR=/tmp
WORKDIR /work
ENTRYPOINT ["stickslip"]
CMD ["--help"]
