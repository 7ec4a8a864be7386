"""A local OpenAI-compatible chat-completions server that answers from a script.

It speaks the real protocol (``POST /v1/chat/completions``) on 127.0.0.1, so the whole LM path
(DSPy, the HTTP client, retries, parsing) runs without a provider. Replies come from a *script*:
an ordered list of rules, each matching a substring of the last user message and giving the reply
text (with its ``finish_reason``), or an HTTP status to fail with, a raw body that is not a chat
completion (a gateway's HTML page), a dropped connection, or a delay. It is a development and test tool; the replies it
serves are whatever script it is given.

Run it: ``python -m robotool.program.standin SCRIPT.json --port 8000 [--log requests.jsonl]``, then point
robotool at ``--lm openai/standin --api-base http://127.0.0.1:8000/v1``. With a log file, each
request is appended to it as one JSON line with the status and reply it got.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import socket
import threading
import time
from collections.abc import Sequence
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path
from typing import Any

from pydantic import BaseModel, Field

SHUTDOWN_POLL_S = 0.02
"""How often the serving thread checks whether it is asked to stop: leaving the ``with`` block waits up to this."""


class Rule(BaseModel):
    """One scripted answer: used for requests whose last user message contains ``match``."""

    match: str = ""
    reply: str = ""
    status: int = Field(200, description="HTTP status; not 200 sends an error body instead of a reply")
    delay: float = Field(0.0, ge=0, description="seconds to wait before answering")
    times: int | None = Field(None, description="use this rule at most this many times, then skip it")
    error_code: str | None = Field(None, description="the error body's code, e.g. 'insufficient_quota'")
    body: str | None = Field(
        None, description="send this text as the whole response body instead (a gateway's HTML page, garbage)"
    )
    content_type: str = Field("text/html", description="the Content-Type of a raw ``body``")
    choices: int = Field(1, ge=0, description="how many choices a reply has (0: an empty choice list)")
    finish_reason: str = Field("stop", description="why the reply ended, e.g. 'length' when cut off at max_tokens")
    drop: bool = Field(False, description="close the connection without answering")


class Script(BaseModel):
    """The stand-in's whole behaviour: rules tried in order, plus a default delay."""

    note: str = Field("", description="what this script is, for people reading it")
    rules: list[Rule]
    delay: float = Field(0.0, ge=0, description="seconds added before every answer")


class StandinServer:
    """The server, run in a background thread; ``base_url`` ends in ``/v1``."""

    def __init__(self, script: Script, port: int = 0, log: Path | None = None):
        self.script = script
        self.log = log
        self.requests: list[dict[str, Any]] = []
        self.authorizations: list[str | None] = []
        """The Authorization header of each request, in the order of :attr:`requests`."""
        self._uses = [0] * len(script.rules)
        self._lock = threading.Lock()
        handler = _handler_for(self)
        self._server = ThreadingHTTPServer(("127.0.0.1", port), handler)
        self._server.daemon_threads = True
        self._thread = threading.Thread(target=self._server.serve_forever, args=(SHUTDOWN_POLL_S,), daemon=True)

    @property
    def base_url(self) -> str:
        host, port = self._server.server_address[:2]
        assert isinstance(host, str)  # an IPv4 server's address
        return f"http://{host}:{port}/v1"

    def __enter__(self) -> StandinServer:
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._server.shutdown()
        self._server.server_close()

    def pick(self, body: dict[str, Any], authorization: str | None = None) -> Rule | None:
        """The first rule that matches the request's last user message and has uses left."""
        messages = body.get("messages") or []
        last_user: dict[str, Any] = next((m for m in reversed(messages) if m.get("role") == "user"), {})
        text = _text(last_user.get("content", ""))
        with self._lock:
            self.requests.append(body)
            self.authorizations.append(authorization)
            for i, rule in enumerate(self.script.rules):
                if rule.match in text and (rule.times is None or self._uses[i] < rule.times):
                    self._uses[i] += 1
                    return rule
        return None

    def record(self, body: dict[str, Any], status: int, reply: str | None) -> None:
        """Append one request and what it got to the log file, if there is one."""
        if self.log is None:
            return
        line = json.dumps({"time": time.time(), "request": body, "status": status, "reply": reply})
        with self._lock, self.log.open("a", encoding="utf-8") as f:
            f.write(line + "\n")


def _text(content: Any) -> str:
    if isinstance(content, list):
        return "".join(part.get("text", "") for part in content if isinstance(part, dict))
    return str(content)


def _handler_for(server: StandinServer) -> type[BaseHTTPRequestHandler]:
    class Handler(BaseHTTPRequestHandler):
        def log_message(self, format: str, *args: Any) -> None:
            return

        def _send(self, status: int, payload: dict[str, Any] | str, content_type: str = "application/json") -> None:
            data = (payload if isinstance(payload, str) else json.dumps(payload)).encode()
            self.send_response(status)
            self.send_header("Content-Type", content_type)
            self.send_header("Content-Length", str(len(data)))
            if status == 429:
                self.send_header("Retry-After", "0")
            self.end_headers()
            with contextlib.suppress(BrokenPipeError, ConnectionResetError):  # the client gave up
                self.wfile.write(data)

        def do_POST(self) -> None:
            if not self.path.rstrip("/").endswith("/chat/completions"):
                self._send(404, {"error": {"message": f"no route {self.path}", "type": "not_found"}})
                return
            length = int(self.headers.get("Content-Length", 0))
            try:
                body = json.loads(self.rfile.read(length) or b"{}")
            except json.JSONDecodeError:
                self._send(400, {"error": {"message": "body is not JSON", "type": "invalid_request_error"}})
                return
            rule = server.pick(body, self.headers.get("Authorization"))
            time.sleep(server.script.delay + (rule.delay if rule else 0.0))
            if rule is None:
                server.record(body, 500, None)
                self._send(500, {"error": {"message": "no scripted reply matches", "type": "server_error"}})
                return
            if rule.drop:
                server.record(body, 0, None)
                self.close_connection = True
                with contextlib.suppress(OSError):
                    self.connection.shutdown(socket.SHUT_RDWR)
                return
            if rule.body is not None:
                server.record(body, rule.status, rule.body)
                self._send(rule.status, rule.body, rule.content_type)
                return
            server.record(body, rule.status, rule.reply if rule.status == 200 else None)
            if rule.status != 200:
                error = {"message": f"scripted status {rule.status}", "type": "server_error", "code": rule.error_code}
                self._send(rule.status, {"error": error})
                return
            words = len(rule.reply.split())
            prompt = sum(len(_text(m.get("content", "")).split()) for m in body.get("messages", []))
            self._send(
                200,
                {
                    "id": "chatcmpl-standin",
                    "object": "chat.completion",
                    "created": int(time.time()),
                    "model": body.get("model", "standin"),
                    "choices": [
                        {
                            "index": i,
                            "finish_reason": rule.finish_reason,
                            "message": {"role": "assistant", "content": rule.reply},
                        }
                        for i in range(rule.choices)
                    ],
                    "usage": {"prompt_tokens": prompt, "completion_tokens": words, "total_tokens": prompt + words},
                },
            )

    return Handler


def main(argv: Sequence[str] | None = None) -> None:
    """Serve a script until interrupted."""
    parser = argparse.ArgumentParser(prog="python -m robotool.program.standin", description=__doc__.split("\n")[0])
    parser.add_argument("script", type=Path, help="JSON file with {'rules': [...], 'delay': seconds}")
    parser.add_argument("--port", type=int, default=8000)
    parser.add_argument("--log", type=Path, metavar="FILE", help="append each request and its reply to this JSONL file")
    args = parser.parse_args(argv)
    script = Script.model_validate_json(args.script.read_text())
    with StandinServer(script, args.port, log=args.log) as server:
        print(f"serving {len(script.rules)} scripted rules at {server.base_url} (Ctrl-C stops)", flush=True)
        with contextlib.suppress(KeyboardInterrupt):
            threading.Event().wait()


if __name__ == "__main__":
    main()
