"""Which parts a furniture model of an opt-in (CC-BY) Sweet Home 3D library plays in egogen's
dwellings (`Role` in src/scene/dwelling/catalogue.rs, in snake case), proposed from its name,
category and size; tools/furniture_catalogue.py writes them into the library's catalogue.json
(`roles`). Standard library only (tested by tests/tools/test_furniture_roles.py).
"""

import re


# The parts a model may play in a dwelling (egogen's `Role`, src/scene/dwelling/catalogue.rs, in
# snake case). The shipped CC0 library's roles are a table there; an opt-in library's are
# proposed here, from each model's name, category and size, and written into its
# catalogue.json (`roles`), where they can be read and edited.
ROLES = (
    "sofa", "armchair", "dining_table", "dining_chair", "desk", "desk_chair", "stool", "bed",
    "nightstand", "wardrobe", "bookcase", "tv_cabinet", "kitchen_unit", "sink_unit", "cooktop",
    "fridge", "tall_unit", "wall_unit", "toilet", "washbasin", "shower", "towel_rack", "plant",
    "floor_thing", "radiator", "table_thing", "kitchen_thing", "bathroom_thing", "bedroom_thing",
)
NOT_A_THING = ("plug", "switch", "socket", "antenna", "dimmer", "rj45", "detector", "intercom",
               "cctv", "surveillance", "bill", "ring", "pencil", "knife", "fork", "spoon")


def proposed_roles(name: str, category: str, width_cm: float, depth_cm: float, height_cm: float,
                   elevation_cm: float, light: bool) -> list[str]:
    """The roles a model of an opt-in library plays, from its Sweet Home 3D entry: by its
    name's words, its category and its size, within the sizes the shipped library's models of
    each role have."""
    words = set(re.findall(r"[a-z0-9]+", name.lower()))
    has = lambda *ws: any(w in words for w in ws)  # noqa: E731
    w, d, h, el = width_cm / 100, depth_cm / 100, height_cm / 100, elevation_cm / 100
    c = category
    if light or c == "Lights" or c == "Doors and windows" or min(w, d, h) < 0.002:
        return []
    between = lambda x, lo, hi: lo <= x <= hi  # noqa: E731
    roles: list[str] = []
    if has("sofa", "couch") and not has("corner", "bench", "convertible", "opened") and between(w, 1.4, 2.4) and between(d, 0.65, 1.0) and between(h, 0.65, 1.05):
        roles.append("sofa")
    if has("armchair") and not has("ottoman") and between(w, 0.55, 1.1) and between(d, 0.5, 1.0) and between(h, 0.65, 1.1):
        roles.append("armchair")
    if has("chair") and not has("armchair", "bar", "high", "baby", "wheelchair", "children", "child") and between(w, 0.38, 0.7) and between(d, 0.4, 0.7) and between(h, 0.75, 1.2):
        roles += ["desk_chair"] if c == "Office" else ["dining_chair", "desk_chair"]
    if has("table") and not has("coffee", "bedside", "night", "bar", "tennis", "football", "pool", "technical", "dressing", "changing", "children", "trestles") and c in ("Living room", "Kitchen", "Office") and between(h, 0.72, 0.8) and between(w, 0.9, 2.4) and between(d, 0.7, 1.3):
        roles.append("dining_table")
    if has("desk") and not has("lamp") and between(h, 0.7, 0.8) and between(w, 0.9, 1.9) and between(d, 0.5, 0.95):
        roles.append("desk")
    if has("stool") and not has("bar") and between(h, 0.4, 0.8):
        roles.append("stool")
    if has("bed") and not has("baby", "bunk", "mezzanine", "hospital", "air", "sofa", "day", "side") and c == "Bedroom" and between(w, 0.9, 2.1) and between(d, 1.9, 2.3) and between(h, 0.35, 1.3):
        roles.append("bed")
    if (has("bedside", "nightstand") or {"night", "table"} <= words) and between(h, 0.35, 0.75) and w <= 0.7:
        roles.append("nightstand")
    if has("wardrobe", "closet", "armoire") and between(h, 1.7, 2.5) and between(d, 0.45, 0.75) and between(w, 0.8, 2.5):
        roles.append("wardrobe")
    if has("bookcase", "shelves", "bookshelf") and not has("upper") and el == 0 and between(h, 0.7, 2.3) and d <= 0.5 and w <= 2.0:
        roles.append("bookcase")
    if has("tv") and has("stand", "cabinet", "unit") and between(h, 0.4, 1.7):
        roles.append("tv_cabinet")
    if c == "Kitchen" and has("cabinet") and not has("upper", "high", "tall", "corner", "glass", "wall", "sink") and el == 0 and between(w, 0.3, 1.2) and between(d, 0.5, 0.7) and between(h, 0.8, 0.95):
        roles.append("kitchen_unit")
    if c == "Kitchen" and has("sink") and el == 0 and between(d, 0.5, 0.7) and between(h, 0.8, 1.25):
        roles.append("sink_unit")
    if (has("cooktop", "hob") or {"induction", "cooker"} <= words) and h <= 0.1 and w >= 0.5:
        roles.append("cooktop")
    if has("fridge", "refrigerator") and between(h, 1.4, 2.1):
        roles.append("fridge")
    if c == "Kitchen" and has("cabinet") and has("high", "tall") and between(h, 1.8, 2.3) and between(d, 0.5, 0.7):
        roles.append("tall_unit")
    if c == "Kitchen" and has("cabinet") and has("upper", "glass", "wall") and between(el, 1.3, 1.7) and d <= 0.45:
        roles.append("wall_unit")
    if has("toilet", "toilets", "wc") and not has("brush", "paper", "dispenser", "tissue") and c == "Bathroom" and between(h, 0.6, 0.9):
        roles.append("toilet")
    if has("washbasin", "vanity") and c == "Bathroom" and el == 0 and between(h, 0.75, 1.0) and w <= 1.2:
        roles.append("washbasin")
    if has("shower") and has("stall", "cabin") and between(h, 1.8, 2.3):
        roles.append("shower")
    if {"towel", "rack"} <= words and c == "Bathroom" and el <= 1.0:
        roles.append("towel_rack")
    if has("plant", "ficus", "yucca", "bonsai", "spathiphyllum", "bamboo", "flowers", "tulips", "lily", "orchids") and between(h, 0.2, 1.9) and max(w, d) <= 1.1:
        roles.append("plant")
    if has("guitar", "speaker", "umbrella", "dustbin", "trash", "recycling", "backpack") and between(h, 0.25, 1.2) and max(w, d) <= 0.6:
        roles.append("floor_thing")
    if has("radiator") and el <= 0.2 and h <= 0.9:
        roles.append("radiator")
    if max(w, d) <= 0.35 and between(h, 0.005, 0.35) and el == 0 and not has(*NOT_A_THING):
        if c in ("Kitchen", "Living room", "Office", "Miscellaneous"):
            roles.append("table_thing")
        if c == "Kitchen":
            roles.append("kitchen_thing")
        if c == "Bathroom":
            roles.append("bathroom_thing")
        if c == "Bedroom":
            roles.append("bedroom_thing")
    return roles
