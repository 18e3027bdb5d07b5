"""The commands' argument parser (benchmark.commands.parser): one line and exit 2 for every refusal."""

import pytest

from benchmark.commands.parser import OneLineParser


def _refusal(capsys, argv):
    p = OneLineParser(prog="prog")
    p.add_argument("--n", type=int, default=1)
    p.add_argument("--x", type=float, default=0.0)
    p.add_argument("--name", default="a")
    with pytest.raises(SystemExit) as e:
        p.parse_args(argv)
    err = capsys.readouterr().err
    assert e.value.code == 2 and err.count("\n") == 1 and err.startswith("prog: error: "), err
    return err


def test_every_refusal_is_one_line_naming_the_bad_value(capsys):
    assert "argument --n: invalid int value: 'two'" in _refusal(capsys, ["--n", "two"])
    assert "argument --name: expected a value, got ' '" in _refusal(capsys, ["--name", " "])
    assert "argument --x: expected a finite number, got 'nan'" in _refusal(capsys, ["--x", "nan"])
    assert "argument --x: expected a finite number, got 'inf'" in _refusal(capsys, ["--x", "inf"])
    assert "unrecognized arguments: --y" in _refusal(capsys, ["--y", "1"])


def test_good_values_parse():
    p = OneLineParser(prog="prog")
    p.add_argument("--x", type=float)
    assert p.parse_args(["--x", "2.5"]).x == 2.5


@pytest.mark.parametrize("module", ["atlas", "colour_ablation", "direct_curve", "humanness", "learning_curve"])
def test_the_commands_refuse_in_one_line(capsys, module):
    import importlib

    main = importlib.import_module(f"benchmark.commands.{module}").main
    with pytest.raises(SystemExit) as e:
        main(["--no-such-option", "1"])
    err = capsys.readouterr().err
    assert e.value.code == 2 and err.count("\n") == 1, err
    assert err.startswith(f"python -m benchmark.commands.{module}: error: "), err  # argparse's usage lines: gone
