"""Running `myriad render` for Blender: finding the program, starting it, reading its
progress and errors, receiving its image after every pass over tev's display protocol (the
`--display` stream myriad sends tev), and stopping it.

The display protocol (tev's, as myriad's `tev_client` writes it): each packet is a u32
length (itself included), a type byte and its fields, little-endian; CreateImage (4) names
the image and its channels, UpdateImage (6, "V3") carries float channels at given offsets
and strides. Strings end with a zero byte.
"""

import os
import queue
import re
import shutil
import socket
import struct
import subprocess
import threading

import numpy as np

PROGRESS = re.compile(r"(\d+)% \((\d+)/(\d+)\)")


class RunError(Exception):
    """myriad could not be found or started, or failed; the message says what to do."""


def find_binary(setting):
    """The myriad executable: the add-on's setting, else MYRIAD_BIN, else `myriad` on PATH."""
    for candidate, where in ((setting, "the add-on's Executable setting"), (os.environ.get("MYRIAD_BIN"), "MYRIAD_BIN")):
        if candidate:
            path = os.path.abspath(os.path.expanduser(candidate))
            if not (os.path.isfile(path) and os.access(path, os.X_OK)):
                raise RunError(f"{where} names '{candidate}', which is not an executable file; give myriad's path")
            return path
    found = shutil.which("myriad")
    if found is None:
        raise RunError(
            "myriad's executable was not found: set it in Render Properties › myriad › Executable, set MYRIAD_BIN, "
            "or put myriad on the PATH (cargo install --path . in its repository)"
        )
    return found


def check_binary(path):
    """An error unless `path` is myriad (it answers `--version` with its name)."""
    try:
        out = subprocess.run([path, "--version"], capture_output=True, text=True, timeout=20)
    except (OSError, subprocess.TimeoutExpired) as e:
        raise RunError(f"'{path}' could not be run ({e}); give myriad's executable") from None
    if out.returncode != 0 or not out.stdout.startswith("myriad"):
        first = (out.stdout.strip().splitlines() or [''])[0][:60]
        raise RunError(f"'{path}' is not myriad (it answered '{first}'); give myriad's executable")


class _DisplayServer:
    """Listens on localhost for myriad's display stream and keeps the latest image."""

    def __init__(self):
        self.server = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        self.server.bind(("127.0.0.1", 0))
        self.server.listen(1)
        self.server.settimeout(0.2)
        self.port = self.server.getsockname()[1]
        self.latest = None
        self.lock = threading.Lock()
        self.stop = threading.Event()
        self.thread = threading.Thread(target=self._serve, daemon=True)
        self.thread.start()

    def take(self):
        """The image received since the last call: (width, height, {channel: array}), or None."""
        with self.lock:
            frame, self.latest = self.latest, None
        return frame

    def close(self):
        self.stop.set()
        self.thread.join(timeout=2)
        self.server.close()

    def _serve(self):
        conn = None
        while not self.stop.is_set() and conn is None:
            try:
                conn, _ = self.server.accept()
            except socket.timeout:
                continue
            except OSError:
                return
        if conn is None:
            return
        conn.settimeout(0.2)
        buf = b""
        size = None
        with conn:
            while not self.stop.is_set():
                try:
                    data = conn.recv(1 << 20)
                except socket.timeout:
                    continue
                except OSError:
                    return
                if not data:
                    return
                buf += data
                while len(buf) >= 4:
                    length = struct.unpack_from("<I", buf)[0]
                    if length < 5 or len(buf) < length:
                        break
                    packet, buf = buf[4:length], buf[length:]
                    size = self._packet(packet, size)

    def _packet(self, p, size):
        kind = p[0]
        pos = 1

        def string():
            nonlocal pos
            end = p.index(b"\0", pos)
            s = p[pos:end].decode()
            pos = end + 1
            return s

        if kind == 4:  # CreateImage: grab focus, name, width, height, channels, names
            pos += 1
            string()
            w, h, _ = struct.unpack_from("<III", p, pos)
            return (w, h)
        if kind == 6:  # UpdateImage V3
            pos += 1
            string()
            (n,) = struct.unpack_from("<I", p, pos)
            pos += 4
            names = [string() for _ in range(n)]
            x, y, w, h = struct.unpack_from("<IIII", p, pos)
            pos += 16
            offsets = struct.unpack_from(f"<{n}Q", p, pos)
            pos += 8 * n
            strides = struct.unpack_from(f"<{n}Q", p, pos)
            pos += 8 * n
            data = np.frombuffer(p, dtype="<f4", offset=pos)
            pixels = w * h
            channels = {
                name: data[o : o + (pixels - 1) * s + 1 : s].reshape(h, w) for name, o, s in zip(names, offsets, strides)
            }
            with self.lock:
                self.latest = (w, h, channels)
        return size


class Render:
    """One running `myriad render` with its display stream."""

    def __init__(self, binary, args):
        self.display = _DisplayServer()
        self.messages = queue.Queue()
        self.errors = []
        self.warnings = []
        self.progress = 0.0
        try:
            self.proc = subprocess.Popen(
                [binary, *args, "--display", f"127.0.0.1:{self.display.port}"],
                stdout=subprocess.PIPE,
                stderr=subprocess.PIPE,
                text=True,
                errors="replace",
            )
        except OSError as e:
            self.display.close()
            raise RunError(f"could not start '{binary}' ({e})") from None
        self.readers = [
            threading.Thread(target=self._read, args=(self.proc.stderr,), daemon=True),
            threading.Thread(target=self._read, args=(self.proc.stdout,), daemon=True),
        ]
        for t in self.readers:
            t.start()

    def _read(self, stream):
        for line in stream:
            self.messages.put(line.rstrip("\n"))

    def poll(self):
        """Reads what myriad said since the last call; returns the new image, if any."""
        while True:
            try:
                line = self.messages.get_nowait()
            except queue.Empty:
                break
            match = PROGRESS.search(line)
            if match:
                done, total = int(match.group(2)), int(match.group(3))
                self.progress = done / total if total else 0.0
            elif line.startswith("error: "):
                self.errors.append(line[len("error: "):])
            elif line.startswith("warning"):
                text = line.split(":", 1)[1].strip() if line.startswith("warning:") else line[len("warning"):].strip()
                self.warnings.append(text)
        return self.display.take()

    def running(self):
        return self.proc.poll() is None

    def stop(self):
        """Ends the render at once (SIGTERM: myriad writes nothing)."""
        if self.proc.poll() is None:
            self.proc.terminate()
            try:
                self.proc.wait(timeout=10)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()

    def finish(self):
        """Waits for the end: the exit status and the last image not yet taken (the stream
        ends when myriad exits). Everything it said has been read."""
        code = self.proc.wait()
        for t in self.readers:
            t.join(timeout=5)
        self.display.thread.join(timeout=5)
        frame = self.poll()
        self.display.close()
        return code, frame
