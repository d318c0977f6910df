#!/usr/bin/env python3
"""How a rendered take's wearers see their own hands (docs/HANDS.md): per camera, the share of
frames in which a wearer's hand landmark projects into the valid field of view, the share in
which one is visible, and of the visible landmarks the share that lands on the wearer's own
segmentation (within `--tolerance-px`, default 1 px: landmarks lie on the hand's surface or
inside it, so a visible one should fall on its body's pixels) and, where the frame files hold
the body parts (`segmentation.part`), the share that lands on that hand's own mask.

    python3 tools/hand_view_stats.py TAKE [--camera camera-rgb] [--json OUT [--replace]]

Needs numpy and OpenEXR, and egogen's reader (`pip install ./python`, or run from the checkout).
"""

import sys
from pathlib import Path

import arguments
import outputs


def stats(take: Path, camera: str, tolerance: int) -> dict:
    import numpy as np

    sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "python"))
    from egogen import reader

    t = reader.Take(take)
    doc = t.annotations(camera)
    wearer = doc["wearer"]
    in_view = visible_frames = visible = on_mask = on_hand = 0
    with_parts = True
    per_landmark_visible = np.zeros(21, int)
    for frame in t.frames(camera):
        me = next(a for a in frame.agents if a["name"] == wearer)
        hands = me.get("hands")
        if not hands:
            raise SystemExit(f"{take}: {wearer} has no hands in {camera}'s annotations (frame {frame.index})")
        seen = [(side, k, h["landmarks_2d"][k]) for side, h in enumerate(hands) for k in range(21)
                if h["landmark_visibility"][k] == "visible"]
        if any(p is not None for h in hands for p in h["landmarks_2d"]):
            in_view += 1
        if not seen:
            continue
        visible_frames += 1
        px = frame.read()
        seg = np.squeeze(np.asarray(px["segmentation"])).astype(np.int64)
        part = px.get("body_part")
        with_parts = with_parts and part is not None
        h_px, w_px = seg.shape
        for side, k, (x, y) in seen:
            visible += 1
            per_landmark_visible[k] += 1
            xi, yi = int(round(x)), int(round(y))
            y0, y1 = max(0, yi - tolerance), min(h_px, yi + tolerance + 1)
            x0, x1 = max(0, xi - tolerance), min(w_px, xi + tolerance + 1)
            mine = seg[y0:y1, x0:x1] == me["id"]
            on_mask += int(mine.any())
            if part is not None:
                hand = np.squeeze(np.asarray(part))[y0:y1, x0:x1] == side + 1
                on_hand += int((mine & hand).any())
    n = len(doc["frames"])
    return {
        "take": str(take),
        "camera": camera,
        "wearer": wearer,
        "frames": n,
        "frames_with_a_hand_landmark_in_view": in_view,
        "frames_with_a_hand_landmark_visible": visible_frames,
        "visible_landmarks": visible,
        "visible_landmarks_on_the_wearers_mask": on_mask,
        "share_on_mask": on_mask / visible if visible else None,
        "visible_landmarks_on_the_hands_mask": on_hand if with_parts else None,
        "share_on_hand_mask": on_hand / visible if visible and with_parts else None,
        "visible_per_landmark": per_landmark_visible.tolist(),
    }


def main() -> None:
    ap = arguments.StrictParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("take", type=Path)
    ap.add_argument("--camera", default="camera-rgb")
    ap.add_argument("--tolerance-px", type=int, default=1)
    ap.add_argument("--json", type=Path)
    ap.add_argument("--replace", action="store_true", help="overwrite an existing --json")
    a = ap.parse_args()
    if a.json:
        outputs.check_new(a.json, "--json", a.replace)
        outputs.check_outside(a.json, "--json", a.take, "the take")
    s = stats(a.take, a.camera, a.tolerance_px)
    print(
        f"{s['take']} {s['camera']} ({s['wearer']}): {s['frames']} frames; a hand landmark in view in "
        f"{s['frames_with_a_hand_landmark_in_view']}, visible in {s['frames_with_a_hand_landmark_visible']}; "
        f"{s['visible_landmarks_on_the_wearers_mask']} of {s['visible_landmarks']} visible landmarks on the wearer's mask"
        + (f", {s['visible_landmarks_on_the_hands_mask']} on that hand's own mask"
           if s["visible_landmarks_on_the_hands_mask"] is not None else "")
    )
    if a.json:
        outputs.write_json(a.json, s, a.replace)


if __name__ == "__main__":
    main()
