"""tools/furniture_roles.py on its own (standard library only; run by tests/tool_outputs.rs):

    python3 tests/tools/test_furniture_roles.py

The parts proposed for real entries of Sweet Home 3D's CC-BY libraries (name, category, width,
depth, height and elevation in cm, as their catalogues give them), and the part names against
egogen's `Role` enum, which reads them.
"""
import re
import sys
import unittest
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent.parent
sys.path.insert(0, str(ROOT / "tools"))
import furniture_roles  # noqa: E402


def roles(name, category, w, d, h, el=0.0, light=False):
    return furniture_roles.proposed_roles(name, category, w, d, h, el, light)


class ProposedRoles(unittest.TestCase):
    def test_seating_by_name_and_size(self):
        self.assertEqual(roles("Chair", "Living room", 42, 47, 88), ["dining_chair", "desk_chair"])
        self.assertEqual(roles("Chair", "Office", 64, 64, 100), ["desk_chair"])
        self.assertEqual(roles("Sofa 3 seats", "Living room", 223, 74, 88), ["sofa"])
        self.assertEqual(roles("Armchair", "Living room", 79, 78, 100), ["armchair"])
        self.assertEqual(roles("Stool", "Living room", 43, 43, 46), ["stool"])
        # A bar chair, a child's chair, a corner sofa: no part of the shipped library's sizes.
        self.assertEqual(roles("Bar chair", "Kitchen", 45, 49, 108), [])
        self.assertEqual(roles("Children chair", "Living room", 28, 28, 51), [])
        self.assertEqual(roles("Corner sofa", "Living room", 346, 155, 85), [])

    def test_tables_beds_and_kitchen_units(self):
        self.assertEqual(roles("Black table", "Living room", 170, 90, 75), ["dining_table"])
        self.assertEqual(roles("Coffee table", "Living room", 144, 64, 51), [])
        self.assertEqual(roles("Desk", "Office", 140, 81, 72), ["desk"])
        self.assertEqual(roles("Bed", "Bedroom", 171, 217, 111), ["bed"])
        self.assertEqual(roles("Bunk bed", "Bedroom", 113, 205, 160), [])
        self.assertEqual(roles("Lower cabinet", "Kitchen", 98, 62, 88), ["kitchen_unit"])
        self.assertEqual(roles("Upper cabinet", "Kitchen", 109, 32, 77, el=145), ["wall_unit"])
        self.assertEqual(roles("Sink", "Kitchen", 98, 62, 98), ["sink_unit"])

    def test_small_things_by_room_and_never_a_wall_fitting_or_a_light(self):
        self.assertEqual(roles("Cup", "Kitchen", 12, 12, 7), ["table_thing", "kitchen_thing"])
        self.assertEqual(roles("Phone", "Office", 20, 22, 7), ["table_thing"])
        self.assertEqual(roles("Soap", "Bathroom", 11, 5, 20), ["bathroom_thing"])
        self.assertEqual(roles("Doll", "Bedroom", 14, 12, 16), ["bedroom_thing"])
        self.assertEqual(roles("Wall switch", "Miscellaneous", 9, 1, 9, el=115), [])
        self.assertEqual(roles("Smoke detector", "Miscellaneous", 10, 2, 10), [])
        self.assertEqual(roles("Kitchen knife", "Kitchen", 4, 26, 2), [])
        self.assertEqual(roles("Desk lamp", "Lights", 14, 34, 45), [])
        self.assertEqual(roles("Lamp", "Living room", 30, 30, 41, light=True), [])
        self.assertEqual(roles("Ring", "Bedroom", 2, 2, 0.1), [])

    def test_every_part_is_one_egogen_reads(self):
        source = (ROOT / "src/scene/dwelling/catalogue.rs").read_text(encoding="utf-8")
        enum = re.search(r"pub enum Role \{(.*?)\n\}", source, re.S).group(1)
        variants = re.findall(r"^\s+([A-Z][A-Za-z]*),", enum, re.M)
        snake = [re.sub(r"(?<!^)([A-Z])", r"_\1", v).lower() for v in variants]
        self.assertEqual(list(furniture_roles.ROLES), snake)


if __name__ == "__main__":
    unittest.main()
