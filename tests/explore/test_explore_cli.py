"""``mechatron explore``: bad arguments fail before a server starts."""

from __future__ import annotations

from mechatron.cli import EXIT_USAGE, main


def test_unknown_model_fails_with_a_suggestion(capsys):
    assert main(["explore", "dc_motr", "--no-browser"]) == EXIT_USAGE
    err = capsys.readouterr().err
    assert "dc_motor" in err and err.count("\n") == 1


def test_a_file_that_is_not_a_simlog(tmp_path, capsys):
    path = tmp_path / "notes.csv"
    path.write_text("time,x\n0,1\n")
    assert main(["explore", str(path), "--no-browser"]) == EXIT_USAGE
    assert "first column must be 't'" in capsys.readouterr().err


def test_bad_port(capsys):
    assert main(["explore", "--port", "70000", "--no-browser"]) == EXIT_USAGE
    assert "--port must be 0 to 65535" in capsys.readouterr().err


def test_help_lists_explore(capsys):
    try:
        main(["explore", "--help"])
    except SystemExit:
        pass
    assert "127.0.0.1" in capsys.readouterr().out
