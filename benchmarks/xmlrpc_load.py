"""A minimal XML-RPC load client: one keep-alive socket, pre-encoded requests, count replies.

Usage: python xmlrpc_load.py PORT SECONDS CALLER WORKLOAD   (WORKLOAD: state | register)
Prints the number of completed calls. The same client drives every master it is compared on.
"""

import socket
import sys
import time
import xmlrpc.client


def request(method, params):
    body = xmlrpc.client.dumps(params, method).encode()
    head = (
        "POST / HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Type: text/xml\r\n"
        f"Content-Length: {len(body)}\r\n\r\n"
    )
    return head.encode() + body


def main():
    port, seconds, caller, workload = int(sys.argv[1]), float(sys.argv[2]), sys.argv[3], sys.argv[4]
    api = f"http://127.0.0.1:{40000 + abs(hash(caller)) % 20000}/"
    if workload == "state":
        cycle = [request("getSystemState", (caller,))]
    else:
        topic = f"/bench{caller}"
        cycle = [
            request("registerPublisher", (caller, topic, "std_msgs/String", api)),
            request("unregisterPublisher", (caller, topic, api)),
        ]
    sock = socket.create_connection(("127.0.0.1", port))
    sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    done = 0
    buf = b""
    deadline = time.perf_counter() + seconds
    while time.perf_counter() < deadline:
        for req in cycle:
            sock.sendall(req)
            while True:
                end = buf.find(b"\r\n\r\n")
                if end >= 0:
                    head = buf[:end].lower()
                    i = head.find(b"content-length:")
                    length = int(head[i + 15 :].split(b"\r\n", 1)[0])
                    if len(buf) >= end + 4 + length:
                        buf = buf[end + 4 + length :]
                        break
                data = sock.recv(262144)
                if not data:
                    raise SystemExit("server closed the connection")
                buf += data
            done += 1
    print(done)


if __name__ == "__main__":
    main()
