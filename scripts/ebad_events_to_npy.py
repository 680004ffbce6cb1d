#!/usr/bin/env python3
"""Convert an EBAD-NeRF ``events.pt`` into ``events.npy`` for EvFlow.

EBAD-NeRF stores its events as a PyTorch pickle: signed per-pixel event counts of shape
[N_views, bins, H*W] (one row per view in poses_bounds.npy order, pixel index y * W + x).
EvFlow does not link PyTorch, so run this once in your own Python environment (it needs
``torch`` and ``numpy``; EvFlow's build and tests never run it):

    python3 scripts/ebad_events_to_npy.py path/to/scene/events.pt            # writes events.npy next to it
    python3 scripts/ebad_events_to_npy.py events.pt -o other/events.npy --dtype int16

The result is a plain little-endian C-order .npy (float32 by default) that
``evflow::io::load_dataset`` reads from the scene folder. Accepted inputs: a tensor, a list/tuple
of per-view tensors (stacked), or a dict holding one of those under "events" (or its only value).
A 2-D [N_views, H*W] tensor is treated as a single bin.
"""
import argparse
import os
import sys

import numpy as np
import torch


def to_array(obj):
    if isinstance(obj, dict):
        if "events" in obj:
            obj = obj["events"]
        elif len(obj) == 1:
            obj = next(iter(obj.values()))
        else:
            sys.exit(f"events.pt holds a dict with keys {list(obj)}; expected 'events'")
    if isinstance(obj, (list, tuple)):
        obj = torch.stack([torch.as_tensor(o) for o in obj])
    arr = torch.as_tensor(obj).detach().cpu().numpy()
    if arr.ndim == 2:
        arr = arr[:, None, :]
    if arr.ndim != 3:
        sys.exit(f"expected counts of shape [N_views, bins, H*W], got {arr.shape}")
    return arr


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("events_pt")
    ap.add_argument("-o", "--output", help="output .npy (default: events.npy next to the input)")
    ap.add_argument("--dtype", default="float32", choices=["float32", "float64", "int16", "int32"])
    args = ap.parse_args()
    out = args.output or os.path.join(os.path.dirname(os.path.abspath(args.events_pt)), "events.npy")
    arr = to_array(torch.load(args.events_pt, map_location="cpu"))
    arr = np.ascontiguousarray(arr.astype(np.dtype(args.dtype).newbyteorder("<")))
    np.save(out, arr)
    print(f"{out}: shape {arr.shape} ({arr.shape[0]} views, {arr.shape[1]} bins, {arr.shape[2]} pixels), {arr.dtype}")


if __name__ == "__main__":
    main()
