"""The lab's /proc readers that the service tests lean on to see what a process left running
or open (`lab/processes.py`)."""

import os
import socket
import subprocess
import sys
import time

from lab.processes import alive, listening_sockets, sockets_held

# A process whose main thread ends (pthread_exit) while another thread, blocked on stdin,
# keeps a listening socket open: its leader reads "Z" in /proc/<pid>/stat, as a
# multi-threaded server's does while its threads are still being torn down.
LEADER_ENDS_FIRST = """
import ctypes, socket, sys, threading
listener = socket.socket()
listener.bind(("127.0.0.1", 0))
listener.listen()
threading.Thread(target=sys.stdin.read).start()
print(listener.getsockname()[1], flush=True)
ctypes.CDLL(None).pthread_exit(None)
"""


def _leader_state(pid: int) -> str:
    with open(f"/proc/{pid}/stat") as stat:
        return stat.read().rsplit(")", 1)[1].split()[0]


def test_a_process_whose_leader_thread_ended_is_alive_until_its_last_thread_ends():
    """Alive while any thread runs, though its leader reads "Z" (reading the leader alone,
    the helper once told a test that a server had ended while its port still listened);
    gone, with its socket closed, once the last thread ends."""
    child = subprocess.Popen([sys.executable, "-c", LEADER_ENDS_FIRST], stdin=subprocess.PIPE,
                             stdout=subprocess.PIPE, text=True)
    try:
        port = int(child.stdout.readline())
        deadline = time.monotonic() + 30
        while _leader_state(child.pid) != "Z":
            assert time.monotonic() < deadline, "the main thread did not end"
            time.sleep(0.01)
        (listener,) = listening_sockets(port)
        assert alive(child.pid)
        child.stdin.close()  # the last thread's read returns: the process ends
        assert child.wait(30) == 0
        assert not alive(child.pid)
        assert listener not in listening_sockets()
    finally:
        if child.poll() is None:
            child.kill()
            child.wait()


def test_sockets_held_and_listening_sockets_follow_a_socket_by_its_inode():
    with socket.socket() as listener:
        listener.bind(("127.0.0.1", 0))
        listener.listen()
        port = listener.getsockname()[1]
        (inode,) = listening_sockets(port)
        assert inode in sockets_held(os.getpid())
    assert inode not in listening_sockets()
