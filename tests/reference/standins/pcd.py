"""A binary PCD reader for the stand-ins: the fields of an uncompressed `DATA binary` file as
named float arrays (what `simulate --layout apollo|ncd` writes; other encodings are refused)."""
import numpy as np

TYPES = {("F", 4): "<f4", ("F", 8): "<f8", ("I", 1): "<i1", ("I", 2): "<i2", ("I", 4): "<i4",
         ("U", 1): "<u1", ("U", 2): "<u2", ("U", 4): "<u4"}


def read_fields(path):
    with open(path, "rb") as f:
        raw = f.read()
    header = {}
    pos = 0
    while True:
        end = raw.index(b"\n", pos)
        line = raw[pos:end].decode("ascii").strip()
        pos = end + 1
        if not line or line.startswith("#"):
            continue
        key, *values = line.split()
        header[key] = values
        if key == "DATA":
            break
    if header["DATA"] != ["binary"]:
        raise ValueError(f"{path}: DATA {header['DATA']}: the stand-in reads binary PCD only")
    counts = header.get("COUNT", ["1"] * len(header["FIELDS"]))
    if any(c != "1" for c in counts):
        raise ValueError(f"{path}: COUNT {counts}: the stand-in reads single-count fields only")
    dtype = np.dtype([(name, TYPES[(t, int(s))])
                      for name, t, s in zip(header["FIELDS"], header["TYPE"], header["SIZE"])])
    n = int(header["POINTS"][0])
    return np.frombuffer(raw, dtype=dtype, count=n, offset=pos)
