"""`springlab fit` on the files people have: separators, decimal commas, comments, units rows, units in column
names, ragged rows, big files, and arrays in memory.

The record is generated here: the free decay's closed form written out below (not springlab.analytic, not
MuJoCo) with seeded white noise, moving at t = 0 (v0 != 0, so no held start is in play). An untidy file
that holds the same numbers as the tidy record must give the same record bit for bit (its text is the
float's repr, read back exactly; a unit is one float multiplication by the unit's factor, done here the
same way), hence the same fit: estimates are compared for equality, not to a tolerance. The tidy fit
itself is checked against the truth: every estimate within two of its 95 % half-widths (about 4 standard
errors: for 5 estimates a 3e-4 chance to miss).
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from springlab.errors import BadInputError
from springlab.studies.fit import data as fit_data
from springlab.studies.fit import reader
from springlab.studies.fit.fit import fit

OMEGA, ZETA, X0, V0, OFFSET, SIGMA = 20.0, 0.05, 0.05, 0.3, 0.002, 1e-4  # rad/s, -, m, m/s, m, m
TRUTH = {"omega_n": OMEGA, "zeta": ZETA, "x0": X0, "v0": V0, "offset": OFFSET}
N, DT = 1000, 2e-3  # samples, s


def decay(t: np.ndarray) -> np.ndarray:
    """x'' + 2 zeta omega x' + omega^2 x = 0 from (X0, V0), plus the offset [m]."""
    wd = OMEGA * math.sqrt(1 - ZETA**2)
    b = (V0 + ZETA * OMEGA * X0) / wd
    return np.exp(-ZETA * OMEGA * t) * (X0 * np.cos(wd * t) + b * np.sin(wd * t)) + OFFSET


T = np.arange(N) * DT
X = decay(T) + np.random.default_rng(7).normal(0.0, SIGMA, N)
_FITS: dict[tuple, object] = {}


def in_units(time_factor: float = 1.0, signal_factor: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """The numbers a file in these units holds (seconds and metres divided by the factors)."""
    return T / time_factor, X / signal_factor


def tidy_fit(time_factor: float = 1.0, signal_factor: float = 1.0):
    """The fit of the tidy record the reader must make of a file in these units (cached)."""
    if (time_factor, signal_factor) not in _FITS:
        t, x = in_units(time_factor, signal_factor)
        t_si = t * time_factor if time_factor != 1.0 else t
        x_si = x * signal_factor if signal_factor != 1.0 else x
        _FITS[time_factor, signal_factor] = fit("slider", {"time": t_si, "slider_pos": x_si}, run_scene=False)
    return _FITS[time_factor, signal_factor]


def tidy_record(time_factor: float = 1.0, signal_factor: float = 1.0):
    """The record read from the tidy arrays in these units (what tidy_fit fits; cached): the reader's claims
    below compare with it, and a record equal bit for bit is fitted to the same estimates (the fit of a file is
    its record's fit, test_the_issues_untidy_file_gives_the_tidy_fit)."""
    key = ("record", time_factor, signal_factor)
    if key not in _FITS:
        t, x = in_units(time_factor, signal_factor)
        t_si = t * time_factor if time_factor != 1.0 else t
        x_si = x * signal_factor if signal_factor != 1.0 else x
        _FITS[key] = fit_data.load({"time": t_si, "slider_pos": x_si}, ("slider",))
    return _FITS[key]


def cells(values: np.ndarray, comma: bool = False) -> list[str]:
    """Each float's repr (read back exactly), with a decimal comma if asked."""
    return [repr(float(v)).replace(".", ",") if comma else repr(float(v)) for v in values]


def text(header: str, sep: str = ",", factors=(1.0, 1.0), comma: bool = False, head: str = "", end: str = "\n"):
    t, x = in_units(*factors)
    rows = [f"{a}{sep}{b}" for a, b in zip(cells(t, comma), cells(x, comma))]
    return head + header + end + end.join(rows) + end


def test_the_tidy_record_gives_the_truth_within_its_intervals():
    result = tidy_fit()
    assert np.array_equal(result.record.time, tidy_record().time)  # what the reader's tests compare with
    assert np.array_equal(result.record.values, tidy_record().values)
    for name, truth in TRUTH.items():
        q = result.estimates[name]
        half = (q["ci95"][1] - q["ci95"][0]) / 2
        assert abs(q["value"] - truth) <= 2 * half, (name, q, truth)


# -- untidy files: the same record and fit as the tidy one, and said so ----------------------------

KINDS = {
    "semicolons": (text("time;slider_pos", ";"), {}, (1, 1), "semicolon-separated"),
    "tabs": (text("time\tslider_pos", "\t"), {}, (1, 1), "tab-separated"),
    "decimal comma, semicolons": (text("time;slider_pos", ";", comma=True), {}, (1, 1), "decimal comma"),
    "decimal comma, tabs": (text("time\tslider_pos", "\t", comma=True), {}, (1, 1), "decimal comma"),
    "comment lines": (
        text("time,slider_pos", head="# logger 2.1\n#  rate: 500 Hz, unit: m\n\n")
        .replace(f"\n{float(T[500])!r},", f"\n# a marker, in the middle\n{float(T[500])!r},")
        .replace(f"{float(X[600])!r}\n", f"{float(X[600])!r}  # a bump, noted\n"),
        {},
        (1, 1),
        "skipped 3 comment line(s)",
    ),
    "units row": (text("time,slider_pos\ns,m"), {}, (1, 1), "units row under the header (line 2): s, m"),
    "units row in mm": (text("time;slider_pos\n[s];[mm]", ";", (1, 1e-3)), {}, (1, 1e-3), "scaled by 0.001 into m"),
    "ms time column": (text("elapsed_ms,slider_pos", factors=(1e-3, 1)), {"elapsed_ms": "time"}, (1e-3, 1), "ms"),
    "time_ms found without a map": (text("time_ms,slider_pos", factors=(1e-3, 1)), {}, (1e-3, 1), "time in ms"),
    "mm column (the issue's file)": (
        text("elapsed_s;disp_mm", ";", (1, 1e-3)),
        {"elapsed_s": "time", "disp_mm": "slider_pos"},
        (1, 1e-3),
        "signal in mm ('disp_mm'): scaled by 0.001 into m",
    ),
    "um column": (text("time,slider_pos_um", factors=(1, 1e-6)), {}, (1, 1e-6), "scaled by 1e-06 into m"),
    "bracketed units": (text("time [ms],slider_pos [mm]", factors=(1e-3, 1e-3)), {}, (1e-3, 1e-3), "time in ms"),
    "round brackets, mapped by name": (
        text("t (s),x (mm)", factors=(1, 1e-3)),
        {"t": "time", "x": "slider_pos"},
        (1, 1e-3),
        "signal in mm ('x (mm)')",
    ),
    "numpy.savetxt's header": (
        text("# time,slider_pos", head="# written by numpy\n"),
        {},
        (1, 1),
        "header read from comment line 2 (as numpy.savetxt writes it)",
    ),
    "a spreadsheet's export": (
        text('"Zeit (s)";"Weg (mm)"', ";", (1, 1e-3), comma=True, head="\ufeff", end="\r\n"),
        {"Zeit": "time", "Weg": "slider_pos"},
        (1, 1e-3),
        "semicolon-separated, decimal comma",
    ),
}


@pytest.mark.parametrize("kind", KINDS)
def test_an_untidy_file_gives_the_tidy_record_and_says_what_it_read(tmp_path, kind):
    # the reader's claim, on every kind of file: the tidy record bit for bit (so the tidy fit: below, through
    # fit() on the issue's file; a fit per kind cost 15 fits of the same record)
    content, mapping, factors, said = KINDS[kind]
    path = tmp_path / "record.csv"
    path.write_bytes(content.encode("utf-8"))
    record = fit_data.load(path, ("slider",), mapping=mapping)
    tidy = tidy_record(*factors)
    assert np.array_equal(record.time, tidy.time)
    assert np.array_equal(record.values, tidy.values)
    assert any(said in note for note in record.notes), record.notes
    assert not any(note.startswith("warning") for note in record.notes)


def test_the_issues_untidy_file_gives_the_tidy_fit(tmp_path):
    content, mapping, factors, said = KINDS["mm column (the issue's file)"]
    path = tmp_path / "record.csv"
    path.write_bytes(content.encode("utf-8"))
    result = fit("slider", path, map=mapping, run_scene=False)
    tidy = tidy_fit(*factors)
    assert np.array_equal(result.record.time, tidy.record.time)
    assert np.array_equal(result.record.values, tidy.record.values)
    assert result.estimates == tidy.estimates
    assert any(said in note for note in result.record.notes), result.record.notes


def test_a_windows_export_with_latin_1_units_in_its_names(tmp_path):
    path = tmp_path / "d.csv"
    path.write_bytes(text("t (s);x (µm)", ";", (1, 1e-6), comma=True, end="\r\n").encode("cp1252"))
    record = fit_data.load(path, ("slider",), mapping={"t": "time", "x": "slider_pos"})
    assert np.array_equal(record.values, tidy_record(1, 1e-6).values)
    assert "signal in µm ('x (µm)'): scaled by 1e-06 into m" in record.notes[1]


@pytest.mark.parametrize("block", [7, 100, 4096])
def test_blocks_of_any_size_read_the_same_record(tmp_path, monkeypatch, block):
    """The body is read in blocks: lines cut at a block's end (or longer than a block) are whole again."""
    path = tmp_path / "record.csv"
    path.write_text(KINDS["comment lines"][0])
    whole = fit_data.load(path, ("slider",))
    monkeypatch.setattr(reader, "BLOCK", block)
    pieces = fit_data.load(path, ("slider",))
    assert np.array_equal(pieces.time, whole.time) and np.array_equal(pieces.values, whole.values)
    assert pieces.notes == whole.notes and pieces.rows == whole.rows == N


# -- refused with one line naming the problem ---------------------------------------------------

ROWS = text("time,slider_pos").splitlines()


def _with(line_number: int, new: str) -> str:
    """ROWS with file line `line_number` (1-based) replaced."""
    lines = list(ROWS)
    lines[line_number - 1] = new
    return "\n".join(lines) + "\n"


@pytest.mark.parametrize(
    ("content", "extra", "message"),
    [
        (_with(700, "1.398,0.01,7"), (), "line 700: 3 fields under a header of 2"),
        (_with(12, "0.021"), (), "line 12: 1 field under a header of 2"),
        (
            text("time,slider_pos", comma=True),
            (),
            "line 2: 4 fields under a header of 2, as if its numbers had decimal",
        ),
        (text("time slider_pos", " "), (), "is one name; a record needs a time and a signal column separated by"),
        (_with(300, "0.598,abc"), (), "line 300: column 'slider_pos' holds 'abc', not a number"),
        ("time,slider_pos\ns\n" + "\n".join(ROWS[1:]), (), "line 2: 1 field under a header of 2"),
        (text("elapsed_s;disp_mm", ";"), ("--map", "t=time"), "d.csv' lacks; its columns: elapsed_s, disp_mm"),
        (text("x [mm],x [V],time", ","), ("--map", "x=slider_pos"), "could be any of 'x [mm]', 'x [V]'"),
        (text("time,slider_pos"), ("--time-scale", "0"), "--time-scale must be a finite positive factor"),
        (text("time,slider_pos"), ("--time-scale", "-0.001"), "--time-scale must be a finite positive factor"),
        (text("time,slider_pos"), ("--scale", "nan"), "--scale must be a finite non-zero factor"),
        ("time,slider_pos\n\0\0", (), "not a text file"),
    ],
)
def test_a_file_it_cannot_read_is_one_line_exit_2(tmp_path, cli, content, extra, message):
    path = tmp_path / "d.csv"
    path.write_text(content)
    code, out, err = cli("fit", "slider", str(path), "--output", str(tmp_path / "out"), *extra)
    assert code == 2 and err.count("\n") == 1 and message in err, err
    assert "Traceback" not in err and not (tmp_path / "out").exists()


def test_a_ragged_row_past_the_first_block_is_named_by_its_line(tmp_path, monkeypatch):
    monkeypatch.setattr(reader, "BLOCK", 256)
    path = tmp_path / "d.csv"
    path.write_text("# header follows\n" + _with(900, "1.798,0.01,3").replace("\n", "\n# c\n", 1))
    # the comment line before the header and the one after it push file line 900 to 902
    with pytest.raises(BadInputError, match="line 902: 3 fields"):
        fit_data.load(path, ("slider",))
    assert path.read_text().splitlines()[901] == "1.798,0.01,3"


# -- units: applied where unambiguous, a warning where not, an explicit factor wins -----------------------


@pytest.mark.parametrize(
    ("header", "mapping", "warning"),
    [
        ("time,slider_pos [V]", {}, "column 'slider_pos [V]' is in 'V', a unit springlab does not know"),
        ("time,vel_ms", {"vel_ms": "slider_pos"}, "says 'ms', a unit of time, but holds slider_pos (a length)"),
        ("time_mm,slider_pos", {}, "says 'mm', a unit of length, but holds the time"),
        ("time,slider_pos_mm\ns,m", {}, "its name says 'mm', the units row 'm': no unit applied"),
    ],
)
def test_a_unit_that_cannot_be_applied_is_a_one_line_warning(tmp_path, cli, header, mapping, warning):
    path = tmp_path / "d.csv"
    path.write_text(text(header))
    record = fit_data.load(path, ("slider",), mapping=mapping)
    assert np.array_equal(record.values, tidy_record().values)  # nothing applied: read as SI
    warnings = [note for note in record.notes if note.startswith("warning: ")]
    assert len(warnings) == 1 and warning in warnings[0] and "FACTOR if it is not" in warnings[0]
    if not mapping:  # on the terminal: one line
        code, out, _ = cli("fit", "slider", str(path))
        assert code in (0, 1) and [line for line in out.splitlines() if "warning" in line] == [f"  {warnings[0]}"]


def test_an_explicit_factor_wins_over_the_columns_unit_and_says_so(tmp_path):
    path = tmp_path / "d.csv"
    path.write_text(text("elapsed_ms,disp_mm", factors=(1e-3, 1e-3)))
    raw_t, raw_x = in_units(1e-3, 1e-3)
    names = {"elapsed_ms": "time", "disp_mm": "slider_pos"}
    agree = fit_data.load(path, ("slider",), mapping=names, scale=1e-3, time_scale=1e-3)
    assert np.array_equal(agree.values, raw_x * 1e-3) and np.array_equal(agree.time, raw_t * 1e-3)
    assert "(--scale agrees)" in agree.notes[0] and "(--time-scale agrees)" in agree.notes[0]
    wins = fit_data.load(path, ("slider",), mapping=names, scale=1.0, time_scale=2e-3)
    assert np.array_equal(wins.values, raw_x) and np.array_equal(wins.time, raw_t * 2e-3)
    assert "--scale wins over 'disp_mm''s mm" in wins.notes[0] and "--time-scale wins" in wins.notes[0]


def test_time_scale_turns_a_millisecond_record_into_the_tidy_fit(tmp_path, cli):
    path = tmp_path / "d.csv"
    path.write_text(text("t,x", factors=(1e-3, 1e-3)))
    code, out, err = cli(
        "fit",
        "slider",
        path,
        "--map",
        "t=time",
        "--map",
        "x=slider_pos",
        "--time-scale",
        "0.001",
        "--scale",
        "0.001",
        "--json",
    )
    doc = json.loads(out)
    assert code in (0, 1) and err == ""
    assert doc["estimates"] == tidy_fit(1e-3, 1e-3).to_dict()["estimates"]
    assert "time scaled by 0.001 into s (--time-scale)" in doc["data_notes"][0]


# -- a big file: streamed in bounded memory, with progress on a terminal ---------------------------------


def test_a_200k_row_file_is_streamed_and_fitted(tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(reader, "BLOCK", 1 << 20)  # 1 MiB: several blocks
    n, dt, sigma = 200_000, 1e-5, 2e-4  # 2 s at 100 kHz
    t = np.arange(n) * dt
    x = decay(t) + np.random.default_rng(11).normal(0.0, sigma, n)
    path = tmp_path / "big.csv"
    with open(path, "w") as handle:
        handle.write("time_s;disp_mm\n")
        np.savetxt(handle, np.column_stack([t, 1e3 * x]), fmt=["%.5f", "%.6f"], delimiter=";")
    assert path.stat().st_size > 2 * reader.BLOCK
    result = fit("slider", path, map={"disp_mm": "slider_pos"}, run_scene=False, show_progress=True)
    assert result.record.time.size == n
    for name, truth in TRUTH.items():
        q = result.estimates[name]
        half = (q["ci95"][1] - q["ci95"][0]) / 2
        assert abs(q["value"] - truth) <= 2 * half, (name, q, truth)
    err = capsys.readouterr().err
    assert "reading big.csv" in err and "100%" in err


def test_a_small_file_off_a_terminal_shows_no_progress(tmp_path, capsys):
    path = tmp_path / "d.csv"
    path.write_text(text("time,slider_pos"))
    fit_data.load(path, ("slider",))
    assert capsys.readouterr().err == ""


# -- arrays in memory: the same fit as the CSV -------------------------------------------------------------


def test_arrays_in_memory_give_the_csvs_fit(tmp_path):
    path = tmp_path / "d.csv"
    path.write_text(text("time,slider_pos"))
    from_file = fit("slider", path, run_scene=False)
    from_lists = fit("slider", {"time": list(T), "slider_pos": list(X)}, run_scene=False)
    assert from_lists.estimates == from_file.estimates == tidy_fit().estimates
    assert from_lists.to_dict()["data_notes"] == from_file.to_dict()["data_notes"]


def test_a_dataframe_gives_the_csvs_fit_with_time_as_a_column_or_the_index():
    import pandas as pd

    frame = pd.DataFrame({"time": T, "slider_pos": X})
    assert fit("slider", frame, run_scene=False).estimates == tidy_fit().estimates
    indexed = pd.DataFrame({"slider_pos": X}, index=pd.Index(T, name="time"))
    assert fit("slider", indexed, run_scene=False).estimates == tidy_fit().estimates
    t_ms, x_mm = in_units(1e-3, 1e-3)
    units = pd.DataFrame({"t [ms]": t_ms, "x [mm]": x_mm})
    assert (
        fit("slider", units, map={"t": "time", "x": "slider_pos"}, run_scene=False).estimates
        == tidy_fit(1e-3, 1e-3).estimates
    )


def test_a_dataframe_of_times_and_missing_values_is_read_as_seconds():
    import pandas as pd

    start = pd.Timestamp("2024-05-01 12:00", tz="Europe/Berlin")
    nullable = pd.array([*X[:-1], None], dtype="Float64")
    frame = pd.DataFrame({"slider_pos": nullable}, index=(start + pd.to_timedelta(T, unit="s")).rename("time"))
    record = fit_data.load(frame, ("slider",))
    assert record.skipped_nan == 1 and record.time.size == N - 1
    assert np.allclose(record.time, T[:-1], rtol=0, atol=1e-9)  # datetimes hold whole nanoseconds
    assert "seconds since its first time, 2024-05-01T10:00:00.000 UTC" in record.notes[0]
    lags = pd.DataFrame({"time": pd.to_timedelta(T, unit="s"), "slider_pos": X})
    assert np.allclose(fit_data.load(lags, ("slider",)).time, T, rtol=0, atol=1e-9)


@pytest.mark.parametrize(
    ("data", "message"),
    [
        ({"time": T, "slider_pos": X[:-1]}, "'time' has 1000 values and 'slider_pos' 999"),
        ({"time": T, "slider_pos": ["a"] * N}, "column 'slider_pos' of the mapping holds something other"),
        ({"time": np.column_stack([T, T]), "slider_pos": X}, "has shape (1000, 2); valid: one value per sample"),
        ([T, X], "a mapping of arrays ({'time': t, 'slider_pos': x}) or a pandas DataFrame; got list"),
        ({"t": T, "slider_pos": X}, "the mapping has no 'time' column; its columns: t, slider_pos"),
    ],
)
def test_arrays_it_cannot_use_are_refused_in_one_line(data, message):
    with pytest.raises(BadInputError, match=None) as caught:
        fit("slider", data)
    assert message in str(caught.value) and "\n" not in str(caught.value)
