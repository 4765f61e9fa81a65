"""tiltbox_client: talk to a tiltbox daemon over Zenoh from Python.

    from tiltbox_client import Client
    with Client("tcp/127.0.0.1:7447") as c:
        print(c.scene()["scene"])

`wire` holds the decoders, encoders and the snapshot decoder, usable without Zenoh.
"""

from .wire import DecodeError, SnapshotDecoder, decode, encode

__all__ = ["Client", "DecodeError", "SnapshotDecoder", "decode", "encode"]
__version__ = "0.1.0"


def __getattr__(name):
    if name == "Client":
        from .client import Client

        return Client
    raise AttributeError(name)
