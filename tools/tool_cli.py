"""The command line of the tools CI runs (the gates, bisect, history): a tool's documentation is
its module docstring, so its first paragraph is the `--help` description and the whole of it the
epilog, laid out as written."""
import argparse


def tool_parser(doc: str) -> argparse.ArgumentParser:
    """The argument parser of a tool whose module docstring is `doc`."""
    return argparse.ArgumentParser(description=doc.split("\n\n")[0], epilog=doc,
                                   formatter_class=argparse.RawDescriptionHelpFormatter)
