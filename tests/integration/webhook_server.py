"""A real HTTPS server for the webhook test (tests/integration/notify.rs).

TLS with the given certificate and key; every POST is recorded as a JSON
line (path, Authorization and Content-Type headers, the answer, the body)
in --log; the first --fail-first requests are answered 503, the rest 200.
Prints the port it listens on (127.0.0.1), then serves until killed.
"""

import argparse
import http.server
import json
import ssl

parser = argparse.ArgumentParser()
parser.add_argument("--cert", required=True)
parser.add_argument("--key", required=True)
parser.add_argument("--log", required=True)
parser.add_argument("--fail-first", type=int, default=0)
args = parser.parse_args()
requests = 0


class Hook(http.server.BaseHTTPRequestHandler):
    def do_POST(self):
        global requests
        body = self.rfile.read(int(self.headers.get("Content-Length", 0)))
        requests += 1
        status = 503 if requests <= args.fail_first else 200
        with open(args.log, "a") as log:
            record = {
                "path": self.path,
                "authorization": self.headers.get("Authorization"),
                "content_type": self.headers.get("Content-Type"),
                "status": status,
                "body": body.decode(),
            }
            log.write(json.dumps(record) + "\n")
        self.send_response(status)
        self.send_header("Content-Length", "0")
        self.end_headers()

    def log_message(self, *_):
        pass


server = http.server.HTTPServer(("127.0.0.1", 0), Hook)
context = ssl.SSLContext(ssl.PROTOCOL_TLS_SERVER)
context.load_cert_chain(args.cert, args.key)
server.socket = context.wrap_socket(server.socket, server_side=True)
print(server.server_address[1], flush=True)
server.serve_forever()
