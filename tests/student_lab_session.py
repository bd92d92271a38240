"""A student's JupyterLab session, driven as the browser would: run by the student venv's
Python (``tests/test_student_fresh_venv.py``) against a ``bash run.sh lab`` started there.

``python student_lab_session.py PORT TOKEN NOTEBOOK`` opens /lab and the scripts it loads,
asks for the language list, opens a session on NOTEBOOK (a path under the server's root),
runs its code cells through the kernel's websocket, asks for completions (IPython's, by
jedi) and starts the debugger (debugpy); it prints one JSON object of what it saw.
"""
from __future__ import annotations

import json
import re
import sys
import time
import urllib.error
import urllib.request
import uuid
from pathlib import Path


#: Completions asked for after the notebook ran: (code, cursor, a match that must come back).
COMPLETIONS = (("np.linal", "linalg"),                                   # an installed package
               ("import collections\ncollections.Ordered", "OrderedDict"))   # the standard library's stubs


def main(port: str, token: str, notebook: str) -> dict:
    # websocket-client comes with the student's JupyterLab, not the instructor's venv
    # (pytest --doctest-modules imports this file there).
    import websocket

    base = f"http://127.0.0.1:{port}"
    clock = time.perf_counter()
    seconds: dict[str, float] = {}

    def lap(phase: str) -> None:
        nonlocal clock
        seconds[phase] = round(time.perf_counter() - clock, 2)
        clock = time.perf_counter()

    def get(path: str, method: str = "GET", body: dict | None = None) -> tuple[int, bytes]:
        request = urllib.request.Request(base + path, method=method,
                                         data=None if body is None else json.dumps(body).encode(),
                                         headers={"Authorization": f"token {token}"})
        try:
            with urllib.request.urlopen(request, timeout=120) as response:
                return response.status, response.read()
        except urllib.error.HTTPError as error:
            return error.code, error.read()

    for _ in range(240):
        try:
            get("/api/status")
            break
        except OSError:
            time.sleep(0.5)
    lap("server start")
    seen: dict = {"seconds": seconds}
    status, page = get("/lab")
    scripts = [src.decode() for src in re.findall(rb'<script[^>]+src="([^"]+)"', page)]
    seen["lab"] = {"status": status, "scripts": {src: get(src)[0] for src in scripts}}
    seen["languages"] = json.loads(get("/lab/api/translations")[1])["data"]
    lap("page, scripts, languages")
    status, body = get("/api/sessions", "POST", {"path": notebook, "type": "notebook", "name": "",
                                                 "kernel": {"name": "collision-course"}})
    kernel = json.loads(body)["kernel"]["id"]
    channels = websocket.create_connection(f"ws://127.0.0.1:{port}/api/kernels/{kernel}/channels?token={token}",
                                           timeout=600)
    lap("kernel start")

    def ask(msg_type: str, content: dict, channel: str = "shell") -> tuple[dict, list[str]]:
        msg_id = uuid.uuid4().hex
        channels.send(json.dumps({"header": {"msg_id": msg_id, "msg_type": msg_type, "session": "lab",
                                             "username": "", "version": "5.3", "date": ""},
                                  "parent_header": {}, "metadata": {}, "content": content, "channel": channel}))
        printed = []
        while True:
            message = json.loads(channels.recv())
            if message.get("parent_header", {}).get("msg_id") != msg_id:
                continue
            content = message["content"]
            if message["msg_type"] == "stream":
                printed.append(content["text"])
            elif message["msg_type"] in ("execute_result", "display_data"):
                printed.append(content["data"].get("text/plain", ""))
            elif message["msg_type"] == "error":
                printed.append(f"{content['ename']}: {content['evalue']}")
            if message["channel"] == channel and message["msg_type"].endswith("_reply"):
                return content, printed

    cells = [cell for cell in json.loads(Path(notebook).read_text(encoding="utf-8"))["cells"]
             if cell["cell_type"] == "code"]
    seen["cells"] = []
    for cell in cells:
        start = time.perf_counter()
        reply, printed = ask("execute_request", {"code": "".join(cell["source"]), "silent": False,
                                                 "store_history": True, "user_expressions": {},
                                                 "allow_stdin": False, "stop_on_error": True})
        seen["cells"].append({"status": reply["status"], "seconds": round(time.perf_counter() - start, 2),
                              "printed": "".join(printed)[-2000:]})
    lap("chapter cells")
    ask("execute_request", {"code": "import numpy as np, sympy, Box2D, pymunk", "silent": False})
    lap("imports")
    seen["completions"] = {code: ask("complete_request", {"code": code, "cursor_pos": len(code)})[0]["matches"][:10]
                           for code, _ in COMPLETIONS}
    lap("completions")
    debugger = {}
    for seq, (command, arguments) in enumerate((
            ("initialize", {"clientID": "lab", "adapterID": "python", "pathFormat": "path",
                            "linesStartAt1": True, "columnsStartAt1": True}),
            ("attach", {}), ("debugInfo", {})), start=1):
        reply, _ = ask("debug_request", {"type": "request", "seq": seq, "command": command, "arguments": arguments},
                       channel="control")
        debugger[command] = bool(reply.get("success"))
    seen["debugger"] = debugger
    lap("debugger")
    channels.close()
    get(f"/api/sessions/{json.loads(body)['id']}", "DELETE")
    return seen


if __name__ == "__main__":
    print(json.dumps(main(*sys.argv[1:4])))
