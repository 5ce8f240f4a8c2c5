#!/usr/bin/env python3
"""Sends one frame of N zero bytes to a ZeroMQ socket, speaking ZMTP 3.0 over a plain TCP socket
with the NULL mechanism as a DEALER (RFC 23/ZMTP: a 64-byte greeting, a READY command naming the
socket type, then a message frame with an 8-byte length). No ZeroMQ library is needed, so a test
can send what our own sockets never would, such as a frame over a receiver's size limit.

Usage: tests/zmtp_send.py HOST PORT BYTES
Exits 0 once the frame was written and the connection held for a second; 1 on a refused or
broken handshake."""
import socket
import struct
import sys
import time


def recv_exact(s, n):
    data = b""
    while len(data) < n:
        chunk = s.recv(n - len(data))
        if not chunk:
            raise ConnectionError("the peer closed the connection")
        data += chunk
    return data


def read_command(s):
    flags = recv_exact(s, 1)[0]
    size = struct.unpack(">Q", recv_exact(s, 8))[0] if flags & 0x02 else recv_exact(s, 1)[0]
    return flags, recv_exact(s, size)


def main():
    host, port, size = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
    s = socket.create_connection((host, port), timeout=5)
    # signature (0xFF, 8 bytes padding, 0x7F), version 3.0, mechanism, as-server 0, filler.
    s.sendall(b"\xff" + b"\x00" * 8 + b"\x7f" + b"\x03\x00" + b"NULL".ljust(20, b"\x00") + b"\x00" * 32)
    greeting = recv_exact(s, 64)
    if greeting[0] != 0xFF or greeting[9] != 0x7F or greeting[12:16] != b"NULL":
        print("zmtp_send: the peer is not a ZMTP 3 socket with the NULL mechanism (CURVE on?)", file=sys.stderr)
        return 1
    ready = b"\x05READY" + b"\x0bSocket-Type" + struct.pack(">I", 6) + b"DEALER"
    s.sendall(bytes([0x04, len(ready)]) + ready)
    flags, body = read_command(s)
    if not flags & 0x04 or not body.startswith(b"\x05READY"):
        print("zmtp_send: the peer did not answer READY", file=sys.stderr)
        return 1
    s.sendall(bytes([0x02]) + struct.pack(">Q", size) + b"\x00" * size)  # one long, last frame
    time.sleep(1)
    s.close()
    print(f"zmtp_send: sent a frame of {size} bytes to {host}:{port}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
