#!/usr/bin/python3
"""A TCP relay that delays every byte it forwards, and the probes that measure a network.

Used by tests/system/netfault_test.sh (issue 82): the cluster's processes live in network
namespaces joined by a bridge, and every cluster connection goes through this relay in the
bridge's namespace, which adds a one-way delay per direction.

  delay_relay.py relay --listen 10.78.0.254 --control FILE --map PORT=HOST:PORT [--map ...]
      Listens on LISTEN:PORT for every mapped port and forwards each connection to HOST:PORT.
      FILE holds "DELAY_MS JITTER_MS" and is re-read every 0.2 s (missing or unreadable: no
      delay). Every chunk read is released at max(the previous chunk's release, arrival +
      DELAY +- uniform JITTER), so bytes stay in order. A connection holds at most --cap bytes
      per direction (default 4 MB): it stops reading its source until the destination takes
      them. A FIN is forwarded after the bytes before it, a reset at once. An upstream connect
      that does not complete within --connect-timeout (1 s) closes the client's connection, as
      a SYN without an answer would time out; it is cancelled when the client goes away first. Logs every connection and every change of the control file on stdout.
  delay_relay.py echo-server [--tcp PORT] [--udp PORT]
      Echoes TCP bytes and UDP datagrams back to their sender (binds 0.0.0.0).
  delay_relay.py tcp-rtt HOST PORT [--count N] [--timeout S]
      Round trips of N 64-byte messages, one at a time, over one connection; prints
      "tcp_rtt_ms median=.. min=.. max=.. n=.." and exits 1 when it cannot connect or a round
      trip does not come back within --timeout.
  delay_relay.py udp-loss HOST PORT [--count N] [--rate R] [--wait S]
      Sends N numbered datagrams at R per second, waits S seconds for the last echoes, prints
      "udp_loss sent=.. received=.. loss=.." (a round trip: loss = 1 - P(there) * P(back)).

Python 3 standard library only.
"""
import argparse
import asyncio
import collections
import os
import random
import socket
import statistics
import struct
import sys
import time


def log(msg):
    print(f"{time.strftime('%H:%M:%S')}.{int(time.time() * 1000) % 1000:03d} {msg}", flush=True)


class Control:
    """The delay and jitter (ms) of the control file, re-read every 0.2 s."""

    def __init__(self, path):
        self.path = path
        self.delay = 0.0
        self.jitter = 0.0
        self.read()

    def read(self):
        try:
            with open(self.path) as f:
                fields = f.read().split()
            delay = float(fields[0]) if fields else 0.0
            jitter = float(fields[1]) if len(fields) > 1 else 0.0
        except (OSError, ValueError):
            delay, jitter = 0.0, 0.0
        jitter = max(0.0, min(jitter, delay))  # never a negative delay
        if (delay, jitter) != (self.delay, self.jitter):
            log(f"control: delay {delay:g} ms, jitter {jitter:g} ms (was {self.delay:g} / {self.jitter:g})")
        self.delay, self.jitter = delay, jitter

    async def watch(self):
        while True:
            await asyncio.sleep(0.2)
            self.read()

    def one_way_s(self):
        return (self.delay + random.uniform(-self.jitter, self.jitter)) / 1000.0


class Pipe:
    """One direction of one connection: chunks waiting for their release time."""

    def __init__(self, control, cap):
        self.control = control
        self.cap = cap
        self.queue = collections.deque()  # (release time, bytes or None for a FIN)
        self.pending = 0
        self.last_release = 0.0
        self.forwarded = 0
        self.cond = asyncio.Condition()

    async def pump_in(self, reader):
        loop = asyncio.get_running_loop()
        while True:
            async with self.cond:
                await self.cond.wait_for(lambda: self.pending < self.cap)
            data = await reader.read(65536)
            now = loop.time()
            release = max(self.last_release, now + self.control.one_way_s())
            self.last_release = release
            async with self.cond:
                self.queue.append((release, data or None))
                self.pending += len(data)
                self.cond.notify_all()
            if not data:
                return

    async def pump_out(self, writer):
        loop = asyncio.get_running_loop()
        while True:
            async with self.cond:
                await self.cond.wait_for(lambda: len(self.queue) > 0)
                release = self.queue[0][0]
            wait = release - loop.time()
            if wait > 0:
                await asyncio.sleep(wait)
            now = loop.time()
            chunks = []
            fin = False
            async with self.cond:
                while self.queue and self.queue[0][0] <= now:
                    _, data = self.queue.popleft()
                    if data is None:
                        fin = True
                        break
                    chunks.append(data)
            size = sum(len(c) for c in chunks)
            if chunks:
                writer.write(b"".join(chunks))
                await writer.drain()
                self.forwarded += size
                async with self.cond:
                    self.pending -= size
                    self.cond.notify_all()
            if fin:
                if writer.can_write_eof():
                    writer.write_eof()
                return


def nodelay(writer):
    sock = writer.get_extra_info("socket")
    if sock is not None:
        try:
            sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        except OSError:
            pass


class Relay:
    def __init__(self, control, cap, connect_timeout):
        self.control = control
        self.cap = cap
        self.connect_timeout = connect_timeout
        self.next_id = 0
        self.open = 0

    async def handle(self, target, client_reader, client_writer):
        self.next_id += 1
        cid = self.next_id
        peer = client_writer.get_extra_info("peername")
        local = client_writer.get_extra_info("sockname")
        nodelay(client_writer)
        self.open += 1
        log(f"conn {cid}: {peer[0]}:{peer[1]} -> :{local[1]} -> {target[0]}:{target[1]} opened ({self.open} open)")
        up = Pipe(self.control, self.cap)
        down = Pipe(self.control, self.cap)
        tasks = []
        upstream_writer = None
        reason = "closed"
        try:
            # A client on a real network whose SYN gets no answer times out and tries again (pamdp's
            # sockets after 2 s). Through the relay its connect succeeds at once, so an upstream
            # that does not answer within --connect-timeout closes the client's connection, which
            # then tries again, as it would without the relay (the kernel's own SYN retries back
            # off to tens of seconds and would make a healed link look dead for that long).
            connect = asyncio.ensure_future(
                asyncio.wait_for(asyncio.open_connection(target[0], target[1]), self.connect_timeout)
            )
            read_client = asyncio.ensure_future(up.pump_in(client_reader))
            tasks = [connect, read_client]
            await asyncio.wait([connect, read_client], return_when=asyncio.FIRST_COMPLETED)
            if not connect.done():
                connect.cancel()
                reason = "client left before the upstream connect completed"
                if read_client.exception() is not None:
                    reason += f" ({read_client.exception()!r})"
                return
            if connect.exception() is not None:
                reason = f"upstream connect failed: {connect.exception()!r}"
                return
            upstream_reader, upstream_writer = connect.result()
            nodelay(upstream_writer)
            log(f"conn {cid}: upstream {target[0]}:{target[1]} connected")
            tasks += [
                asyncio.ensure_future(up.pump_out(upstream_writer)),
                asyncio.ensure_future(down.pump_in(upstream_reader)),
                asyncio.ensure_future(down.pump_out(client_writer)),
            ]
            pending = set(tasks[1:])
            while pending:
                done, pending = await asyncio.wait(pending, return_when=asyncio.FIRST_COMPLETED)
                errors = [t.exception() for t in done if t.exception() is not None]
                if errors:
                    reason = f"reset ({errors[0]!r})"
                    return
        except Exception as e:  # noqa: BLE001 (a relay logs and drops a connection, never dies)
            reason = f"error {e!r}"
        finally:
            for t in tasks:
                if not t.done():
                    t.cancel()
            for w in (client_writer, upstream_writer):
                if w is not None:
                    w.transport.abort() if reason.startswith(("reset", "error")) else w.close()
            self.open -= 1
            log(f"conn {cid}: {reason}; forwarded {up.forwarded} B up, {down.forwarded} B down ({self.open} open)")

    async def run(self, listen, maps):
        servers = []
        for port, target in maps:
            server = await asyncio.start_server(
                lambda r, w, target=target: self.handle(target, r, w), listen, port, reuse_address=True
            )
            servers.append(server)
            log(f"listening on {listen}:{port} -> {target[0]}:{target[1]}")
        log("relay ready")
        await self.control.watch()


def cmd_relay(args):
    maps = []
    for m in args.map:
        port, target = m.split("=", 1)
        host, tport = target.rsplit(":", 1)
        maps.append((int(port), (host, int(tport))))
    control = Control(args.control)
    asyncio.run(Relay(control, args.cap, args.connect_timeout).run(args.listen, maps))


def cmd_echo_server(args):
    async def echo(reader, writer):
        nodelay(writer)
        try:
            while True:
                data = await reader.read(65536)
                if not data:
                    break
                writer.write(data)
                await writer.drain()
        except OSError:
            pass
        finally:
            writer.close()

    class Udp(asyncio.DatagramProtocol):
        def connection_made(self, transport):
            self.transport = transport

        def datagram_received(self, data, addr):
            self.transport.sendto(data, addr)

    async def main():
        if args.tcp:
            await asyncio.start_server(echo, "0.0.0.0", args.tcp, reuse_address=True)
        if args.udp:
            await asyncio.get_running_loop().create_datagram_endpoint(Udp, local_addr=("0.0.0.0", args.udp))
        log(f"echo server ready (tcp {args.tcp}, udp {args.udp})")
        await asyncio.Event().wait()

    asyncio.run(main())


def cmd_tcp_rtt(args):
    try:
        sock = socket.create_connection((args.host, args.port), timeout=args.timeout)
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        rtts = []
        for i in range(args.count):
            msg = struct.pack("!I", i) * 16
            start = time.monotonic()
            sock.sendall(msg)
            got = b""
            while len(got) < len(msg):
                chunk = sock.recv(len(msg) - len(got))
                if not chunk:
                    raise ConnectionError("closed by the peer")
                got += chunk
            rtts.append((time.monotonic() - start) * 1000.0)
            if got != msg:
                raise ValueError("echo differs")
        sock.close()
    except (OSError, ValueError) as e:
        print(f"tcp_rtt_ms failed={e!r}", flush=True)
        return 1
    print(
        f"tcp_rtt_ms median={statistics.median(rtts):.1f} min={min(rtts):.1f} max={max(rtts):.1f} n={len(rtts)}",
        flush=True,
    )
    return 0


def cmd_udp_loss(args):
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sock.setblocking(False)
    sock.connect((args.host, args.port))
    seen = set()
    sent = 0
    start = time.monotonic()
    end = None

    def drain():
        while True:
            try:
                data = sock.recv(64)
            except (BlockingIOError, ConnectionRefusedError):
                return
            if len(data) >= 4:
                seen.add(struct.unpack("!I", data[:4])[0])

    while True:
        now = time.monotonic()
        if sent < args.count and now >= start + sent / args.rate:
            try:
                sock.send(struct.pack("!I", sent) + b"x" * 28)
            except OSError:
                pass  # a partitioned sender: counted as lost
            sent += 1
            if sent == args.count:
                end = time.monotonic() + args.wait
        drain()
        if end is not None and time.monotonic() >= end:
            break
        time.sleep(0.0005)
    received = len(seen)
    print(f"udp_loss sent={sent} received={received} loss={1 - received / sent:.4f}", flush=True)
    return 0


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="cmd", required=True)
    p = sub.add_parser("relay")
    p.add_argument("--listen", required=True)
    p.add_argument("--control", required=True)
    p.add_argument("--map", action="append", required=True, help="PORT=HOST:PORT")
    p.add_argument("--cap", type=int, default=4 << 20, help="bytes pending per direction per connection")
    p.add_argument("--connect-timeout", type=float, default=1.0, help="seconds for the upstream connect")
    p = sub.add_parser("echo-server")
    p.add_argument("--tcp", type=int, default=0)
    p.add_argument("--udp", type=int, default=0)
    p = sub.add_parser("tcp-rtt")
    p.add_argument("host")
    p.add_argument("port", type=int)
    p.add_argument("--count", type=int, default=20)
    p.add_argument("--timeout", type=float, default=3.0)
    p = sub.add_parser("udp-loss")
    p.add_argument("host")
    p.add_argument("port", type=int)
    p.add_argument("--count", type=int, default=500)
    p.add_argument("--rate", type=float, default=500.0)
    p.add_argument("--wait", type=float, default=1.0)
    args = parser.parse_args()
    rc = {"relay": cmd_relay, "echo-server": cmd_echo_server, "tcp-rtt": cmd_tcp_rtt, "udp-loss": cmd_udp_loss}[
        args.cmd
    ](args)
    sys.exit(rc or 0)


if __name__ == "__main__":
    os.environ.setdefault("PYTHONUNBUFFERED", "1")
    main()
