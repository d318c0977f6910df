"""The command lines of egogen's tools: an option that takes one value is refused when it is
given more than once, as egogen's Rust commands refuse it, rather than the later value
silently winning (`--camera a --camera b` would run on b).

    import arguments
    ap = arguments.StrictParser(description=...)   # an argparse.ArgumentParser
    ...
    args = ap.parse_args()

`StrictParser` refuses, with argparse's usage line and exit status 2, a second occurrence of
any option whose action stores one value (store, store_const, store_true, store_false,
argparse.BooleanOptionalAction), in either form (`--opt v`, `--opt=v`) and under any of its
spellings (`-o` and `--out` are one option; `--flag` and `--no-flag` too). Options that
collect (append, extend, count) stay repeatable; positional arguments are untouched; the
parsers `add_subparsers()` makes are StrictParsers too. Tools that read `sys.argv` by hand
take their switches with `switch(argv, "--replace")`, which refuses a repeat the same way.

Standard library only. Scripts import it from tools/ (`python3 tools/x.py` puts tools/ on
sys.path; one run another way, e.g. under `blender --python`, inserts its own folder first).
"""
import argparse
import os
import sys

# The actions that store one value; their subclasses (store_true, store_false) included.
SINGLE = (argparse._StoreAction, argparse._StoreConstAction, argparse.BooleanOptionalAction)


def given_twice(name, first, second):
    """The message for an option given a second time."""
    return f"argument {name}: given twice ({first}, {second}); give it once"


class _Once:
    """Mixed in before a single-value action's class: the action's second call in one parse
    (one occurrence on the command line each) is an argparse error naming both."""

    def __call__(self, parser, namespace, values, option_string=None):
        given = getattr(parser, "_given", None)
        if given is not None:  # None: called by a parser that is not strict (parents=[...])
            if given[0] is not namespace:  # a new parse
                given[:] = [namespace, {}]
            text = parser._occurrence(self, option_string, values)
            first = given[1].get(self)
            if first is not None:
                raise argparse.ArgumentError(self, f"given twice ({first}, {text}); give it once")
            given[1][self] = text
        super().__call__(parser, namespace, values, option_string)


_strict_classes = {}


def _strict_class(cls):
    if cls not in _strict_classes:
        _strict_classes[cls] = type(f"Once{cls.__name__}", (_Once, cls), {})
    return _strict_classes[cls]


class StrictParser(argparse.ArgumentParser):
    """An argparse.ArgumentParser that refuses a single-value option given more than once
    (see the module's docstring). Its sub-parsers are StrictParsers (argparse makes them of
    the parser's own class)."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self._given = [None, {}]  # [the namespace being parsed, {action: first occurrence}]
        self._raw = (None, None)  # (action, its argument strings) of the occurrence now taken

    def _make_strict(self):
        # Every action is checked when parsing starts, whichever way it was added (add_argument
        # on the parser, on a group, or copied from parents=[...]): a single-value option's
        # action gets the subclass that counts its occurrences.
        for action in self._actions:
            if action.option_strings and isinstance(action, SINGLE) and not isinstance(action, _Once):
                action.__class__ = _strict_class(type(action))
        self._given[:] = [None, {}]

    def parse_known_args(self, args=None, namespace=None):
        self._make_strict()
        return super().parse_known_args(args, namespace)

    def parse_known_intermixed_args(self, args=None, namespace=None):
        self._make_strict()
        return super().parse_known_intermixed_args(args, namespace)

    def _get_values(self, action, arg_strings):
        # argparse converts an occurrence's strings just before calling its action: kept, so
        # the refusal quotes the command line rather than the converted values.
        self._raw = (action, list(arg_strings))
        return super()._get_values(action, arg_strings)

    def _occurrence(self, action, option_string, values):
        """One occurrence as given: the option and its argument strings."""
        raw_action, raw = self._raw
        if raw_action is not action:
            raw = [] if action.nargs == 0 else values if isinstance(values, list) else [values]
        return " ".join([option_string or "/".join(action.option_strings)] + [str(v) for v in raw])


def switch(argv, name, prog=None):
    """A switch (an option without a value) in a command line read by hand: `argv` less every
    `name`, and whether `name` was there. A second `name` is refused as StrictParser refuses
    it: `<prog>: error: ...` on stderr, exit status 2.

        args, replace = arguments.switch(sys.argv[1:], "--replace")
    """
    rest = [a for a in argv if a != name]
    if len(argv) - len(rest) > 1:
        prog = prog or os.path.basename(sys.argv[0] or "tool")
        sys.stderr.write(f"{prog}: error: {given_twice(name, name, name)}\n")
        sys.exit(2)
    return rest, len(rest) < len(argv)
