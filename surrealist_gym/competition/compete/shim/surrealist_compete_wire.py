"""The wire between ``surrealist compete`` and a tool's shim: JSON only, never pickle.

Each message is one JSON object (UTF-8), preceded by its length as 4 bytes, big-endian, and at most
:data:`MAX_MESSAGE` bytes; anything else ends the connection. The socket is an ``AF_UNIX`` one in a folder only
this user may enter; the tool's first message is ``{"op": "hello", "key": HEX}`` with the key
``surrealist compete`` gave it (``SURREALIST_COMPETE_AUTHKEY``), compared in constant time. Decoding JSON builds
dicts, lists, strings and numbers, nothing else: a tool cannot run code in the ``compete`` process through it.

Standard library only: the shim imports it in the tool's Python, the server in surrealist-gym's.

Example::

    >>> import socket
    >>> a, b = socket.socketpair()
    >>> send(a, {"op": "fly", "runs": 1}); receive(b)
    {'op': 'fly', 'runs': 1}
"""
import json
import struct

#: The largest message either side accepts [bytes] (a test with thousands of obstacles is a few hundred KB).
MAX_MESSAGE = 4 * 1024 * 1024
_HEADER = struct.Struct(">I")


class WireError(Exception):
    """A message that is not one length-prefixed JSON object within :data:`MAX_MESSAGE`."""


def send(sock, message: dict) -> None:
    """Send one JSON object."""
    data = json.dumps(message, allow_nan=False, separators=(",", ":")).encode("utf-8")
    if len(data) > MAX_MESSAGE:
        raise WireError(f"message of {len(data)} bytes, over the {MAX_MESSAGE} allowed")
    sock.sendall(_HEADER.pack(len(data)) + data)


def receive(sock) -> dict:
    """Receive one JSON object; EOFError when the other side closed before a message, WireError on a bad one."""
    size = _HEADER.unpack(_exactly(sock, _HEADER.size, at_start=True))[0]
    if size > MAX_MESSAGE:
        raise WireError(f"message of {size} bytes announced, over the {MAX_MESSAGE} allowed")
    try:
        message = json.loads(_exactly(sock, size).decode("utf-8"), parse_constant=_no_constant)
    except (UnicodeDecodeError, ValueError, RecursionError):
        raise WireError("a message that is not JSON") from None
    if not isinstance(message, dict):
        raise WireError("a message that is not a JSON object")
    return message


def _exactly(sock, size: int, at_start: bool = False) -> bytes:
    chunks, got = [], 0
    while got < size:
        chunk = sock.recv(min(size - got, 65536))
        if not chunk:
            if at_start and not got:
                raise EOFError("closed")
            raise WireError("connection closed inside a message")
        chunks.append(chunk)
        got += len(chunk)
    return b"".join(chunks)


def _no_constant(name: str):
    raise ValueError(f"{name} is not JSON")
