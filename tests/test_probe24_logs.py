"""A resumed run's earlier logs are data: a ``scalars.csv`` that no run wrote (a field too long for
the CSV reader, bytes that are no UTF-8, a forged row) is refused in one line naming it before
anything trains, and a TensorBoard file whose name lies in the future no longer makes a resumed
run wait for ever."""

from __future__ import annotations

import time
from pathlib import Path

import pytest

from empathy_zoo.cli import main
from empathy_zoo.training.log_files import (
    CLOCK_SLACK_S,
    after_earlier_event_files,
    check_csv_log,
    check_event_file_names,
    keep_csv_rows_up_to,
)
from empathy_zoo.training.tracking import log_dir

GOOD = "step,name,value\n100,charts/SPS,1000.0\n200,eval/harms,0.5\n"


@pytest.mark.parametrize(
    ("text", "why"),
    [
        (GOOD + '300,"' + "x" * 200_000 + '",1.0\n400,a,1.0\n', "line 4: no CSV row"),
        ("step,name,value\n100,a,1.0\n\xff\xfe,b,2\n300,a,1\n", "no UTF-8 text"),
        ("when,what\n100,a,1.0\n", "line 1: the header"),
        (GOOD + "-5,a,1.0\n300,a,1.0\n", "line 4: the step '-5'"),
        (GOOD + "300,a\x1b[2J,1.0\n400,a,1.0\n", "line 4: the name"),
        (GOOD + "300,a,lots\n400,a,1.0\n", "line 4: the value 'lots'"),
        (GOOD + "300,a,1.0,extra\n400,a,1.0\n", "line 4: 4 fields"),
    ],
)
def test_a_csv_log_that_no_run_wrote_is_refused_naming_its_line(tmp_path: Path, text: str, why: str) -> None:
    path = tmp_path / "scalars.csv"
    path.write_bytes(text.encode("utf-8", errors="surrogateescape") if "\xff" not in text else text.encode("latin-1"))
    with pytest.raises(ValueError, match=why) as refused:
        check_csv_log(path)
    assert str(path) in str(refused.value) and "\n" not in str(refused.value)
    before = path.read_bytes()
    with pytest.raises(ValueError, match=why):
        keep_csv_rows_up_to(path, 200)
    assert path.read_bytes() == before, "nothing is rewritten before the file is checked"


def test_only_the_last_row_may_be_cut_short_and_it_is_dropped(tmp_path: Path) -> None:
    path = tmp_path / "scalars.csv"
    path.write_text(GOOD + "300,charts/SP", encoding="utf-8")
    check_csv_log(path)
    keep_csv_rows_up_to(path, 1_000)
    assert path.read_text(encoding="utf-8").splitlines() == GOOD.splitlines()


def test_an_event_file_named_in_the_future_is_refused_and_one_of_now_is_waited_for(tmp_path: Path) -> None:
    now = int(time.time())
    (tmp_path / f"events.out.tfevents.{now}.host.1.0").touch()
    assert check_event_file_names(tmp_path) == now
    after_earlier_event_files(tmp_path)  # (returns within the second)
    assert int(time.time()) > now
    for name in (f"events.out.tfevents.{now + 10 * CLOCK_SLACK_S}.evil", "events.out.tfevents." + "9" * 200 + ".x"):
        evil = tmp_path / name
        evil.touch()
        with pytest.raises(ValueError, match="past this machine's clock") as refused:
            after_earlier_event_files(tmp_path)
        assert str(evil) in str(refused.value)
        evil.unlink()


TRAIN = [
    "train",
    "--steps",
    "400",
    "--eval-interval",
    "400",
    "--eval-episodes",
    "1",
    "--seed",
    "0",
    "--no-progress",
    "--learning-starts",
    "40",
    "--batch-size",
    "8",
    "--replay-capacity",
    "200",
    "--hidden-size",
    "8",
    "--max-cycles",
    "20",
]


@pytest.mark.parametrize("backend", ["csv", "tensorboard"])
def test_train_refuses_a_forged_log_before_anything_trains(tmp_path: Path, capsys, backend: str) -> None:
    if backend == "tensorboard":
        pytest.importorskip("tensorboard")
    assert main([*TRAIN, "--out", str(tmp_path / "first")]) == 0
    (result,) = (tmp_path / "first" / "runs").glob("*.json")
    out = tmp_path / "second"
    place = log_dir(out, backend, result.stem)
    place.mkdir(parents=True)
    forged = place / ("scalars.csv" if backend == "csv" else "events.out.tfevents.99999999999.evil")
    forged.write_text('step,name,value\n1,"' + "x" * 200_000 + '",1\n2,a,1\n' if backend == "csv" else "", encoding="utf-8")
    capsys.readouterr()
    assert main([*TRAIN, "--out", str(out), "--log", backend]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and str(forged) in err, err
    assert not (out / "runs").exists() or not list((out / "runs").glob("*.json")), "nothing trained"
