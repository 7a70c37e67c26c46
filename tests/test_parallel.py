"""fohw._parallel: tasks in order on any executor, and the one progress display."""

import sys

import pytest

from fohw._parallel import progress_bar, run_tasks


def test_progress_is_silent_unless_asked_or_on_a_terminal(capsys):
    bar = progress_bar(3, "job")                    # stderr is captured: not a terminal
    bar.update(1)
    bar.write("stage")
    bar.close()
    assert capsys.readouterr().err == ""


def test_stage_messages_and_the_plain_counter(capsys, monkeypatch):
    monkeypatch.setitem(sys.modules, "tqdm", None)          # tqdm not installed
    monkeypatch.setitem(sys.modules, "tqdm.auto", None)
    stages = progress_bar(None, "robot-arm", True)
    stages.write("structure scan")
    stages.close()
    assert capsys.readouterr().err == "robot-arm: structure scan\n"
    bar = progress_bar(2, "tasks", True)
    bar.update(1)
    bar.update(1)
    bar.close()
    assert capsys.readouterr().err == "\rtasks: 1/2\rtasks: 2/2\n"


@pytest.mark.parametrize("progress", [False, True])
def test_run_tasks_keeps_the_order(progress, capsys):
    assert run_tasks(pow, [(2, 3), (3, 2)], progress=progress) == [8, 9]
