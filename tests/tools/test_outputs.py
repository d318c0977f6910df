"""tools/outputs.py on its own (standard library only; run by tests/tool_outputs.rs):

    python3 tests/tools/test_outputs.py
"""
import os
import subprocess
import sys
import tempfile
import unittest
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent.parent / "tools"))
import outputs  # noqa: E402


class Outputs(unittest.TestCase):
    def setUp(self):
        self._dir = tempfile.TemporaryDirectory()
        self.dir = Path(self._dir.name)

    def tearDown(self):
        self._dir.cleanup()

    def test_an_existing_path_is_refused_unless_replace(self):
        p = self.dir / "sheet.png"
        p.write_bytes(b"mine")
        with self.assertRaises(outputs.OutputError) as e:
            outputs.check_new(p, "--out")
        self.assertIn(f"--out {p}", str(e.exception))
        self.assertIn("choose a new path or pass --replace", str(e.exception))
        self.assertEqual(outputs.check_new(p, "--out", True), p)
        with self.assertRaises(outputs.OutputError) as e:
            outputs.check_new(p, "--work", None)
        self.assertNotIn("--replace", str(e.exception))
        self.assertEqual(p.read_bytes(), b"mine")

    def test_an_error_is_a_system_exit_with_the_message(self):
        p = self.dir / "x.json"
        p.write_text("{}")
        r = subprocess.run(
            [sys.executable, "-c", f"import outputs; outputs.check_new({str(p)!r}, '--json')"],
            capture_output=True, text=True,
            env={**os.environ, "PYTHONPATH": str(Path(outputs.__file__).parent)},
        )
        self.assertEqual(r.returncode, 1)
        self.assertEqual(r.stderr.strip(), f"--json {p}: exists; choose a new path or pass --replace")

    def test_a_missing_folder_is_refused_unless_the_tool_makes_it(self):
        p = self.dir / "no" / "such" / "out.json"
        with self.assertRaises(outputs.OutputError) as e:
            outputs.check_new(p, "--json")
        self.assertIn("no such folder", str(e.exception))
        outputs.check_new(p, "--json", parents=True)

    def test_replace_does_not_swap_a_file_for_a_folder(self):
        (self.dir / "d").mkdir()
        (self.dir / "f").write_text("")
        with self.assertRaises(outputs.OutputError):
            outputs.check_new(self.dir / "d", "--out", True)
        with self.assertRaises(outputs.OutputError):
            outputs.check_new(self.dir / "f", "--out", True, folder=True)
        outputs.check_new(self.dir / "d", "--out", True, folder=True)

    def test_an_output_inside_the_input_is_refused(self):
        take = self.dir / "take"
        (take / "cameras").mkdir(parents=True)
        for inside in [take / "out.json", take / "cameras" / "out.json"]:
            with self.assertRaises(outputs.OutputError) as e:
                outputs.check_outside(inside, "--json", take, "the take")
            self.assertIn(f"--json {inside}: inside the take {take}", str(e.exception))
        with self.assertRaises(outputs.OutputError) as e:
            outputs.check_outside(take, "--out", take, "the take")
        self.assertIn("is the take", str(e.exception))
        # Through a link to the folder, and the same file as a file input.
        (self.dir / "link").symlink_to(take)
        with self.assertRaises(outputs.OutputError):
            outputs.check_outside(self.dir / "link" / "out.json", "--json", take)
        (self.dir / "in.pkl").write_bytes(b"")
        with self.assertRaises(outputs.OutputError):
            outputs.check_outside(self.dir / "in.pkl", "OUT", self.dir / "in.pkl")
        outputs.check_outside(self.dir / "take.json", "--json", take)
        outputs.check_outside(self.dir / "out.json", "--json", self.dir / "in.pkl")

    def test_writing_leaves_the_file_and_no_partial(self):
        p = self.dir / "a.json"
        outputs.write_json(p, {"k": 1})
        self.assertEqual(p.read_text(), '{\n  "k": 1\n}\n')
        outputs.write_text(self.dir / "b.txt", "x\ny\n")
        outputs.write_bytes(self.dir / "c.bin", b"\0\1")
        self.assertEqual((self.dir / "b.txt").read_bytes(), b"x\ny\n")
        self.assertEqual((self.dir / "c.bin").read_bytes(), b"\0\1")
        self.assertEqual(sorted(q.name for q in self.dir.iterdir()), ["a.json", "b.txt", "c.bin"])

    def test_writing_refuses_a_path_that_appeared_and_replace_overwrites(self):
        p = self.dir / "a.txt"
        with self.assertRaises(outputs.OutputError):
            with outputs.writing(p) as tmp:
                tmp.write_text("new")
                p.write_text("mine")  # another program wrote it meanwhile
        self.assertEqual(p.read_text(), "mine")
        self.assertFalse(outputs.partial_path(p).exists())
        outputs.write_text(p, "new", replace=True)
        self.assertEqual(p.read_text(), "new")
        self.assertFalse(outputs.partial_path(p).exists())

    def test_an_error_inside_the_block_removes_the_partial(self):
        p = self.dir / "sheet.png"
        with self.assertRaises(RuntimeError):
            with outputs.writing(p) as tmp:
                self.assertEqual(tmp, self.dir / "sheet.png.partial")
                tmp.write_bytes(b"half")
                raise RuntimeError("the plot failed")
        self.assertEqual(list(self.dir.iterdir()), [])
        # A writing program that fails (here one that writes the partial, then exits 1).
        with self.assertRaises(subprocess.CalledProcessError):
            with outputs.writing(p) as tmp:
                subprocess.run([sys.executable, "-c", f"open({str(tmp)!r}, 'w').write('half'); exit(1)"],
                               check=True)
        self.assertEqual(list(self.dir.iterdir()), [])

    def test_a_block_that_writes_nothing_is_an_error(self):
        with self.assertRaises(outputs.OutputError):
            with outputs.writing(self.dir / "out.png"):
                pass
        self.assertEqual(list(self.dir.iterdir()), [])

    def test_a_partial_left_by_a_killed_run_is_written_over(self):
        p = self.dir / "out.txt"
        outputs.partial_path(p).write_text("stale")
        outputs.write_text(p, "fresh")
        self.assertEqual(p.read_text(), "fresh")
        self.assertFalse(outputs.partial_path(p).exists())

    def test_format_of_follows_the_extension(self):
        self.assertEqual(outputs.format_of("docs/x.PNG"), "png")
        self.assertEqual(outputs.format_of("x.svg"), "svg")
        self.assertEqual(outputs.format_of("x"), "png")


if __name__ == "__main__":
    unittest.main(verbosity=2)
