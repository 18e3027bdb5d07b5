"""fsv.errors: one base class, and messages kept to one line."""

from fsv.errors import FsvError, InputError, one_line


def test_input_error_is_an_fsv_error_and_a_value_error():
    assert issubclass(InputError, FsvError) and issubclass(InputError, ValueError)


def test_one_line_joins_lines_and_cuts_long_messages():
    assert one_line(RuntimeError("first line\n  second\tline\n")) == "first line second line"
    long = one_line(ValueError("x" * 500), limit=50)
    assert len(long) == 50 and long.endswith("...")
