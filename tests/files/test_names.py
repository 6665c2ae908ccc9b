"""files.names: names derived from input."""

import subprocess

import pytest

from quadruped_dyn.files.names import comment_text


@pytest.mark.parametrize("name", ["a*/b", "a/*b", "a/*/b", "*/*/", "/**/", "x*//*y", "//*", "**//"])
def test_comment_text_neither_ends_nor_opens_a_c_comment(name):
    text = comment_text(name)
    assert "*/" not in text and "/*" not in text


def test_a_frame_name_with_a_comment_opener_compiles_in_the_generated_header_s_flags(tmp_path):
    """The generated Makefile builds with -Wall -Werror: a '/*' inside a comment (-Wcomment) was an error."""
    source = tmp_path / "t.c"
    source.write_text(f"/*\n * Feet: FL '{comment_text('FL_a/*b*/c')}'.\n */\nint qd_x;\n")
    run = subprocess.run(["cc", "-std=c99", "-pedantic", "-Wall", "-Wextra", "-Werror", "-c", str(source),
                          "-o", str(tmp_path / "t.o")], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
