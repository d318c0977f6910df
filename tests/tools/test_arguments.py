"""tools/arguments.py on its own (standard library only; run by tests/tool_outputs.rs):

    python3 tests/tools/test_arguments.py
"""
import argparse
import contextlib
import io
import os
import subprocess
import sys
import unittest
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent.parent / "tools"))
import arguments  # noqa: E402


def parser():
    ap = arguments.StrictParser(prog="tool")
    ap.add_argument("take")
    ap.add_argument("extra", nargs="*")
    ap.add_argument("-o", "--out")
    ap.add_argument("--camera", default="camera-rgb")
    ap.add_argument("--frames", type=int)
    ap.add_argument("--replace", action="store_true")
    ap.add_argument("--quiet", action="store_false", dest="loud")
    ap.add_argument("--exact", action="store_const", const="exact")
    ap.add_argument("--color", action=argparse.BooleanOptionalAction)
    ap.add_argument("--tag", action="append")
    ap.add_argument("--item", action="extend", nargs="+")
    ap.add_argument("-v", "--verbose", action="count", default=0)
    group = ap.add_argument_group("grouped")
    group.add_argument("--scene")
    either = ap.add_mutually_exclusive_group()
    either.add_argument("--fast", action="store_true")
    either.add_argument("--slow", action="store_true")
    return ap


class StrictParser(unittest.TestCase):
    def refused(self, ap, argv):
        """The parse ends with exit status 2; what it wrote on stderr."""
        err = io.StringIO()
        with contextlib.redirect_stderr(err), self.assertRaises(SystemExit) as e:
            ap.parse_args(argv)
        self.assertEqual(e.exception.code, 2, err.getvalue())
        return err.getvalue()

    def test_a_value_given_twice_is_refused_naming_both(self):
        err = self.refused(parser(), ["T", "--camera", "a", "--camera", "b"])
        self.assertIn("tool: error: argument --camera: given twice (--camera a, --camera b); give it once", err)
        self.assertIn("usage: tool", err)

    def test_both_forms_count(self):
        for argv in (["--camera=a", "--camera", "b"], ["--camera", "a", "--camera=b"], ["--camera=a", "--camera=b"]):
            err = self.refused(parser(), ["T", *argv])
            self.assertIn("(--camera a, --camera b)", err)

    def test_the_same_value_twice_is_refused_too(self):
        err = self.refused(parser(), ["T", "--frames", "3", "--frames", "3"])
        self.assertIn("argument --frames: given twice (--frames 3, --frames 3)", err)

    def test_an_options_spellings_are_one_option(self):
        for argv in (["-o", "a", "--out", "b"], ["--out=a", "-o", "b"], ["-oa", "-ob"], ["--ou", "a", "--out", "b"]):
            err = self.refused(parser(), ["T", *argv])
            self.assertIn("argument -o/--out: given twice", err)

    def test_switches_are_refused(self):
        for argv, name in (
            (["--replace", "--replace"], "argument --replace: given twice (--replace, --replace)"),
            (["--quiet", "--quiet"], "argument --quiet: given twice"),
            (["--exact", "--exact"], "argument --exact: given twice"),
            (["--color", "--no-color"], "argument --color/--no-color: given twice (--color, --no-color)"),
            (["--color", "--color"], "argument --color/--no-color: given twice"),
            (["--fast", "--fast"], "argument --fast: given twice"),
            (["--scene", "s", "--scene", "s"], "argument --scene: given twice"),
        ):
            self.assertIn(name, self.refused(parser(), ["T", *argv]))

    def test_once_each_parses_as_argparse_does(self):
        argv = ["T", "x", "y", "-o", "o", "--camera=c", "--frames", "5", "--replace", "--quiet",
                "--exact", "--no-color", "--scene", "s", "--slow"]
        strict = parser().parse_args(argv)
        plain = vars(parser().parse_args(argv))
        self.assertEqual(vars(strict), plain)
        self.assertEqual((strict.out, strict.camera, strict.frames, strict.color), ("o", "c", 5, False))
        self.assertEqual(parser().parse_args(["T"]).camera, "camera-rgb")

    def test_collecting_options_and_positionals_stay_repeatable(self):
        a = parser().parse_args(["T", "T", "T", "--tag", "a", "--tag", "b", "--item", "x", "--item", "y", "z",
                                 "-vv", "--verbose", "-v"])
        self.assertEqual((a.take, a.extra), ("T", ["T", "T"]))
        self.assertEqual((a.tag, a.item, a.verbose), (["a", "b"], ["x", "y", "z"], 4))

    def test_a_parser_parses_again_afresh(self):
        ap = parser()
        ap.parse_args(["T", "--camera", "a"])
        self.assertEqual(ap.parse_args(["T", "--camera", "b"]).camera, "b")
        ns = argparse.Namespace()
        ap.parse_args(["T", "--replace"], ns)
        self.assertTrue(ap.parse_args(["T", "--replace"], ns).replace)

    def test_sub_parsers_are_strict(self):
        ap = arguments.StrictParser(prog="tool")
        ap.add_argument("--debug", action="store_true")
        sub = ap.add_subparsers(dest="cmd", required=True)
        rays = sub.add_parser("rays")
        self.assertIsInstance(rays, arguments.StrictParser)
        rays.add_argument("take")
        rays.add_argument("--camera")
        a = ap.parse_args(["--debug", "rays", "T", "--camera", "a"])
        self.assertEqual((a.debug, a.cmd, a.take, a.camera), (True, "rays", "T", "a"))
        err = self.refused(ap, ["rays", "T", "--camera", "a", "--camera", "b"])
        self.assertIn("tool rays: error: argument --camera: given twice (--camera a, --camera b)", err)
        err = self.refused(ap, ["--debug", "--debug", "rays", "T"])
        self.assertIn("tool: error: argument --debug: given twice", err)

    def test_a_plain_parser_sharing_an_action_is_unchanged(self):
        common = argparse.ArgumentParser(add_help=False)
        common.add_argument("--camera")
        strict = arguments.StrictParser(prog="tool", parents=[common])
        self.refused(strict, ["--camera", "a", "--camera", "b"])
        self.assertEqual(common.parse_args(["--camera", "a", "--camera", "b"]).camera, "b")

    def test_exit_on_error_false_raises_the_argument_error(self):
        ap = arguments.StrictParser(prog="tool", exit_on_error=False)
        ap.add_argument("--camera")
        with self.assertRaises(argparse.ArgumentError) as e:
            ap.parse_args(["--camera", "a", "--camera", "b"])
        self.assertEqual(str(e.exception), "argument --camera: given twice (--camera a, --camera b); give it once")

    def test_a_script_exits_with_status_2(self):
        script = ("import arguments; ap = arguments.StrictParser(prog='tool'); "
                  "ap.add_argument('--seed', type=int); print(ap.parse_args().seed)")
        env = {**os.environ, "PYTHONPATH": str(Path(arguments.__file__).parent)}
        r = subprocess.run([sys.executable, "-c", script, "--seed", "1", "--seed=2"],
                           capture_output=True, text=True, env=env)
        self.assertEqual(r.returncode, 2)
        self.assertEqual(r.stdout, "")
        self.assertTrue(r.stderr.rstrip().endswith(
            "tool: error: argument --seed: given twice (--seed 1, --seed 2); give it once"), r.stderr)
        r = subprocess.run([sys.executable, "-c", script, "--seed", "1"], capture_output=True, text=True, env=env)
        self.assertEqual((r.returncode, r.stdout), (0, "1\n"), r.stderr)


class Switch(unittest.TestCase):
    def test_a_switch_is_taken_out(self):
        self.assertEqual(arguments.switch(["a", "--replace", "b"], "--replace"), (["a", "b"], True))
        self.assertEqual(arguments.switch(["a", "b"], "--replace"), (["a", "b"], False))

    def test_a_switch_given_twice_is_refused(self):
        err = io.StringIO()
        with contextlib.redirect_stderr(err), self.assertRaises(SystemExit) as e:
            arguments.switch(["--replace", "a", "--replace"], "--replace", prog="tool.py")
        self.assertEqual(e.exception.code, 2)
        self.assertEqual(err.getvalue(),
                         "tool.py: error: argument --replace: given twice (--replace, --replace); give it once\n")


if __name__ == "__main__":
    unittest.main()
