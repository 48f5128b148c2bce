"""Tests of the network-namespace harness: command plans (recorded) and one real two-host lab (root)."""
import subprocess

import pytest

from mbzirc_robustness import netns


class Recorder:
    def __init__(self):
        self.cmds = []

    def __call__(self, argv):
        self.cmds.append(list(argv))
        return subprocess.CompletedProcess(argv, 0, "", "")


def test_plan_of_a_lab_with_two_hosts_and_a_cut():
    rec = Recorder()
    lab = netns.NetnsLab(prefix="tst", runner=rec).start()
    gs = lab.add_host("gs")
    uav = lab.add_host("uav1")
    assert (gs.ip, uav.ip) == ("10.77.0.1", "10.77.0.2")
    assert gs.ns == f"{lab.lab}-gs" and lab.sw == f"{lab.lab}-sw"
    assert ["ip", "netns", "add", lab.sw] == rec.cmds[0]
    veth = ["ip", "-n", lab.sw, "link", "add", "p2", "type", "veth", "peer", "name", "eth0", "netns", uav.ns]
    assert veth in rec.cmds
    assert ["ip", "-n", uav.ns, "addr", "add", "10.77.0.2/24", "dev", "eth0"] in rec.cmds
    n = len(rec.cmds)
    lab.cut("uav1")
    assert rec.cmds[n:] == [["ip", "-n", lab.sw, "link", "set", "p2", "nomaster"]]
    assert not lab.hosts["uav1"].link_up
    lab.set_link("uav1", True)
    assert rec.cmds[-1][-2:] == ["master", "br0"]
    lab.close()
    dels = [c for c in rec.cmds if c[:3] == ["ip", "netns", "del"]]
    assert [c[3] for c in dels] == [uav.ns, gs.ns, lab.sw], "hosts then switch, all of them"
    lab.close()  # idempotent
    assert len([c for c in rec.cmds if c[:3] == ["ip", "netns", "del"]]) == 3


def test_ros_env_points_at_the_ground_station_and_drops_ros_hostname():
    env = netns.ros_env("10.77.0.1", "10.77.0.3", base={"ROS_HOSTNAME": "localhost", "PATH": "/bin"})
    assert env == {"ROS_MASTER_URI": "http://10.77.0.1:11311", "ROS_IP": "10.77.0.3", "PATH": "/bin"}


def test_lab_namespaces_groups_by_owner_pid():
    names = ["mbzr-12-sw", "mbzr-12-gs (id: 3)", "mbzr-7-uav1", "other-1-gs", "mbzrx-1-gs"]
    assert netns.lab_namespaces(names, "mbzr") == {12: ["mbzr-12-sw", "mbzr-12-gs"], 7: ["mbzr-7-uav1"]}


def _tcp_probe(lab, frm, ip, port):
    code = ("import socket,sys\ns=socket.socket();s.settimeout(1.0)\n"
            f"sys.exit(0 if s.connect_ex(({ip!r},{port}))==0 else 1)")
    return lab.exec(frm, ["/usr/bin/python3", "-c", code], timeout=10).returncode == 0


def test_real_lab_connects_cuts_restores_and_cleans_up():
    prefix = "mbzrtest"
    with netns.NetnsLab(prefix=prefix) as lab:
        lab.add_host("gs")
        lab.add_host("uav1")
        server = lab.popen("gs", ["/usr/bin/python3", "-c",
                                  "import socket,time\ns=socket.socket();s.setsockopt(socket.SOL_SOCKET,"
                                  "socket.SO_REUSEADDR,1);s.bind(('0.0.0.0',5555));s.listen(8)\n"
                                  "while True:\n c,_=s.accept();c.close()"])
        assert netns.wait_tcp(lab, "uav1", "10.77.0.1", 5555, timeout=10)
        lab.cut("uav1")
        assert not _tcp_probe(lab, "uav1", "10.77.0.1", 5555)
        timer = lab.cut("uav1", seconds=0.2)
        timer.join(2.0)
        assert lab.hosts["uav1"].link_up
        assert _tcp_probe(lab, "uav1", "10.77.0.1", 5555)
        names = [lab.hosts["gs"].ns, lab.hosts["uav1"].ns, lab.sw]
    listed = subprocess.run(["ip", "netns", "list"], capture_output=True, text=True).stdout
    assert not any(n in listed for n in names), listed
    assert server.poll() is not None, "server process must be stopped"


def test_stale_lab_of_a_dead_owner_is_removed():
    dead_pid = 4_000_000  # above pid_max: never alive
    ns = f"mbzrtest-{dead_pid}-gs"
    subprocess.run(["ip", "netns", "add", ns], check=True)
    try:
        removed = netns.cleanup_stale("mbzrtest")
        assert ns in removed
        assert ns not in subprocess.run(["ip", "netns", "list"], capture_output=True, text=True).stdout
    finally:
        subprocess.run(["ip", "netns", "del", ns], capture_output=True)


def test_failed_command_raises_with_stderr():
    with pytest.raises(RuntimeError, match="failed"):
        netns.run_cmd(["ip", "link", "show", "no-such-interface-xyz"])
