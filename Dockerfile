# The MBZIRC C3 workspace in a container. It runs the very setup script the README's commands run
# (setup/setup.sh: Debian's ROS packages, the pinned venv, catkin_make), so what CI tests is what ships.
#   docker build -t mbzirc-c3 .
#   docker run --rm -it mbzirc-c3 make mission            # the C3 mission, headless
#   docker compose -f docker/compose.yaml up              # master, simulator, central unit, one container per robot
FROM debian:bookworm
ENV DEBIAN_FRONTEND=noninteractive LANG=C.UTF-8
WORKDIR /opt/mbzirc
# Only what the setup script itself needs to start; it installs the rest.
RUN apt-get update && apt-get install -y --no-install-recommends ca-certificates make util-linux \
    && rm -rf /var/lib/apt/lists/*
# Setup inputs first, so that the apt and pip layers are cached across source edits.
COPY setup/ setup/
COPY catkin_ws/src/ catkin_ws/src/
COPY env.sh Makefile ./
RUN bash setup/setup.sh && rm -rf /var/lib/apt/lists/* /root/.cache/pip
COPY . .
RUN bash setup/setup.sh
ENV ROS_HOSTNAME=localhost ROS_MASTER_URI=http://localhost:11311
ENTRYPOINT ["/opt/mbzirc/docker/entrypoint.sh"]
CMD ["make", "mission"]
