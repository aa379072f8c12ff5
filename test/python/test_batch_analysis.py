#!/usr/bin/python3
"""scripts/batch_analysis and scripts/plot_batch: a tiny batch on the package's own worlds, resuming after a kill,
a Dask LocalCluster giving the rows of the local run, the plots, and bad input.

Needs the built batch_cases (found like the scripts find it: $CMAKE_PREFIX_PATH, else the checkout's .ws); the
tests skip without it, unless HIDDEN_ROOMS_REQUIRE_SHARED=1, when they fail; PlotBatchTest needs no tool (its
results.csv is written by hand: formats, confidence intervals, the LaTeX table). The shared data folder
($HIDDEN_ROOMS_SHARED_DIR or ../shared beside the checkout) is used by one test, which skips when it is absent.
"""
import csv
import math
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
import unittest
from xml.etree import ElementTree

PACKAGE_DIR = os.path.dirname(os.path.dirname(os.path.dirname(os.path.realpath(__file__))))
sys.path.insert(0, os.path.join(PACKAGE_DIR, "src"))
from hidden_rooms import batch_analysis  # noqa: E402

BATCH_SCRIPT = os.path.join(PACKAGE_DIR, "scripts", "batch_analysis")
PLOT_SCRIPT = os.path.join(PACKAGE_DIR, "scripts", "plot_batch")
SMALL_WORLD = os.path.join(PACKAGE_DIR, "worlds", "small_1.xml")
MEDIUM_WORLD = os.path.join(PACKAGE_DIR, "worlds", "medium_1.xml")
METHODS = "default,thesis,unstructured,structured,skewnormal"
TIMING_COLUMNS = {"case_seconds"} | {"seconds_%s" % method for method in METHODS.split(",")}


PLOT_FORMATS = ["png", "pdf", "svg"]
PLOT_STEMS = ["iou_vs_closed_doors", "iou_tot_vs_closed_doors", "iou_by_size_class", "table"]


def required():
    return os.environ.get("HIDDEN_ROOMS_REQUIRE_SHARED") == "1"


def tool_or_skip():
    try:
        return batch_analysis.find_binary(batch_analysis.TOOL_NAME)
    except batch_analysis.ToolError as error:
        if required():
            raise AssertionError("batch_cases not built: %s" % error)
        raise unittest.SkipTest("batch_cases not built: %s" % error)


def script_environment():
    """The tests' environment, with the checkout's Python module importable (for the Dask workers too)."""
    environment = dict(os.environ)
    environment["PYTHONPATH"] = os.pathsep.join(
        [os.path.join(PACKAGE_DIR, "src")] + [p for p in environment.get("PYTHONPATH", "").split(os.pathsep) if p])
    return environment


def run_batch(*arguments, timeout=600):
    return subprocess.run([sys.executable, BATCH_SCRIPT, "--no-progress"] + list(arguments), capture_output=True,
                          text=True, timeout=timeout, env=script_environment())


def run_plot(*arguments):
    return subprocess.run([sys.executable, PLOT_SCRIPT] + list(arguments), capture_output=True, text=True,
                          timeout=300, env=script_environment())


def check_figures(test, out_dir, formats):
    """Every figure of plot_batch in every format: non-empty, a PDF starting with %PDF, an SVG that parses."""
    for stem in PLOT_STEMS:
        for extension in formats:
            path = os.path.join(out_dir, "%s.%s" % (stem, extension))
            test.assertTrue(os.path.isfile(path) and os.path.getsize(path) > 0, path)
            if extension == "pdf":
                with open(path, "rb") as stream:
                    test.assertEqual(stream.read(4), b"%PDF", path)
            elif extension == "svg":
                test.assertTrue(ElementTree.parse(path).getroot().tag.endswith("svg"), path)


def read_rows(out_dir):
    with open(os.path.join(out_dir, "results.csv"), newline="") as stream:
        reader = csv.DictReader(stream)
        return reader.fieldnames, list(reader)


def keyed(rows, drop_timing=True):
    """{(environment, batch, closed doors): row without the timing columns}; fails on a duplicate key."""
    result = {}
    for row in rows:
        key = (row["environment"], int(row["batch"]), int(row["closed_doors"]))
        assert key not in result, "duplicate row %s" % (key,)
        result[key] = {name: value for name, value in row.items() if not (drop_timing and name in TIMING_COLUMNS)}
    return result


class BatchAnalysisTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.binary = tool_or_skip()
        cls.folder = tempfile.mkdtemp(prefix="batch_analysis_test_")
        # The reference: medium_1, 3 batches of up to 12 doors (every closable door), all methods, local.
        cls.reference_dir = os.path.join(cls.folder, "reference")
        cls.reference_args = ["--env", MEDIUM_WORLD, "--batches", "3", "--max-closed", "12", "--methods", METHODS,
                              "--seed", "7", "--binary", cls.binary]
        start = time.monotonic()
        cls.reference = run_batch(*(cls.reference_args + ["--out", cls.reference_dir]))
        cls.reference_seconds = time.monotonic() - start

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.folder, ignore_errors=True)

    def test_tiny_batch_rows(self):
        out_dir = os.path.join(self.folder, "tiny")
        result = run_batch("--env", SMALL_WORLD, "--batches", "2", "--max-closed", "3", "--methods", METHODS,
                           "--out", out_dir, "--seed", "1", "--binary", self.binary)
        self.assertEqual(result.returncode, 0, result.stdout + result.stderr)
        columns, rows = read_rows(out_dir)
        self.assertEqual(columns, batch_analysis.result_columns(METHODS.split(",")))
        self.assertEqual(sorted(keyed(rows)), [("small_1", b, k) for b in (1, 2) for k in (1, 2, 3)])
        by_key = keyed(rows)
        for (environment, batch, closed), row in by_key.items():
            self.assertEqual(row["size_class"], "small")
            doors = row["closed_door_ids"].split()
            self.assertEqual(len(doors), closed)
            if closed > 1:  # cumulative: one more door than the case before
                self.assertEqual(by_key[(environment, batch, closed - 1)]["closed_door_ids"].split(), doors[:-1])
            for method in METHODS.split(","):
                self.assertTrue(0.0 <= float(row["iou_" + method]) <= 1.0)
                self.assertTrue(0.0 <= float(row["iou_tot_" + method]) <= 1.0)
            self.assertGreater(float(row["hidden_percent"]), 0.0)
            self.assertEqual(row["failed_methods"], "")
        self.assertGreater(max(float(row["iou_default"]) for row in rows), 0.5)
        self.assertNotEqual(by_key[("small_1", 1, 3)]["closed_door_ids"], by_key[("small_1", 2, 3)]["closed_door_ids"])
        # Re-running the finished command adds nothing.
        again = run_batch("--env", SMALL_WORLD, "--batches", "2", "--max-closed", "3", "--methods", METHODS,
                          "--out", out_dir, "--seed", "1", "--binary", self.binary)
        self.assertEqual(again.returncode, 0, again.stdout + again.stderr)
        self.assertIn("0 new rows", again.stdout)
        self.assertEqual(len(read_rows(out_dir)[1]), 6)
        # Other settings in the same folder are refused.
        other = run_batch("--env", SMALL_WORLD, "--batches", "2", "--max-closed", "3", "--methods", METHODS,
                          "--out", out_dir, "--seed", "2", "--binary", self.binary)
        self.assertEqual(other.returncode, 2, other.stdout + other.stderr)
        self.assertIn("seed", other.stderr)

    def test_reference_run(self):
        self.assertEqual(self.reference.returncode, 0, self.reference.stdout + self.reference.stderr)
        rows = keyed(read_rows(self.reference_dir)[1])
        self.assertEqual(len(rows), 3 * 12)
        self.assertTrue(all(row["size_class"] == "medium" for row in rows.values()))

    def test_resume_after_kill(self):
        self.assertEqual(self.reference.returncode, 0, self.reference.stderr)
        out_dir = os.path.join(self.folder, "killed")
        results = os.path.join(out_dir, "results.csv")
        command = [sys.executable, BATCH_SCRIPT, "--no-progress", "--out", out_dir, "--jobs", "1"] + self.reference_args
        process = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                                   start_new_session=True, env=script_environment())
        deadline = time.monotonic() + 120
        rows_at_kill = 0
        while time.monotonic() < deadline and process.poll() is None:
            if os.path.isfile(results):
                with open(results) as stream:
                    rows_at_kill = sum(1 for _ in stream) - 1
                if rows_at_kill >= 5:
                    break
            time.sleep(0.02)
        os.killpg(process.pid, signal.SIGKILL)  # the script, its threads and batch_cases
        process.wait()
        self.assertLess(rows_at_kill, 36, "the run finished before it could be killed")
        # As if the kill had cut the last row in the middle of its line.
        with open(results, "a") as stream:
            stream.write("medium_1,medium,3,12,0.5")
        resumed = run_batch(*(self.reference_args + ["--out", out_dir]))
        self.assertEqual(resumed.returncode, 0, resumed.stdout + resumed.stderr)
        columns, rows = read_rows(out_dir)
        self.assertEqual(columns, batch_analysis.result_columns(METHODS.split(",")))
        resumed_rows = keyed(rows)  # asserts no duplicate
        self.assertEqual(resumed_rows, keyed(read_rows(self.reference_dir)[1]))

    def test_dask_local_cluster_gives_the_local_rows(self):
        self.assertEqual(self.reference.returncode, 0, self.reference.stderr)
        try:
            from dask.distributed import LocalCluster
        except ImportError as error:
            if required():
                raise AssertionError("python3-distributed missing: %s" % error)
            raise unittest.SkipTest("python3-distributed missing: %s" % error)
        saved = os.environ.get("PYTHONPATH")
        os.environ["PYTHONPATH"] = script_environment()["PYTHONPATH"]  # the workers import the module
        try:
            with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None,
                              host="127.0.0.1") as cluster:
                out_dir = os.path.join(self.folder, "dask")
                result = run_batch(*(self.reference_args + ["--out", out_dir, "--scheduler",
                                                            cluster.scheduler_address]))
        finally:
            if saved is None:
                os.environ.pop("PYTHONPATH", None)
            else:
                os.environ["PYTHONPATH"] = saved
        self.assertEqual(result.returncode, 0, result.stdout + result.stderr)
        self.assertIn("tcp://127.0.0.1", result.stdout)
        self.assertEqual(keyed(read_rows(out_dir)[1]), keyed(read_rows(self.reference_dir)[1]))

    def test_plot_batch_writes_its_files(self):
        self.assertEqual(self.reference.returncode, 0, self.reference.stderr)
        out_dir = os.path.join(self.folder, "plots")
        tiny_dir = os.path.join(self.folder, "plot_small")
        small = run_batch("--env", SMALL_WORLD, "--batches", "1", "--max-closed", "2", "--methods", METHODS,
                          "--out", tiny_dir, "--binary", self.binary)
        self.assertEqual(small.returncode, 0, small.stderr)
        result = run_plot(self.reference_dir, tiny_dir, "--out", out_dir)
        self.assertEqual(result.returncode, 0, result.stdout + result.stderr)
        check_figures(self, out_dir, PLOT_FORMATS)
        for name in ["table.csv", "table.md", "table.tex"]:
            path = os.path.join(out_dir, name)
            self.assertTrue(os.path.isfile(path) and os.path.getsize(path) > 0, name)
        with open(os.path.join(out_dir, "table.csv"), newline="") as stream:
            table = list(csv.DictReader(stream))
        classes = {row["size_class"] for row in table}
        self.assertEqual(classes, {"small", "medium", "all"})
        medium = [row for row in table if row["size_class"] == "medium" and row["closed_doors"] != "all"]
        self.assertEqual([int(row["closed_doors"]) for row in medium], list(range(1, 13)))
        self.assertTrue(all(int(row["cases"]) == 3 for row in medium))
        for row in medium:  # 3 batches: an interval around the mean
            low, mean, high = (float(row[name]) for name in ("ci_low_default", "iou_default", "ci_high_default"))
            self.assertLessEqual(low, mean)
            self.assertLessEqual(mean, high)
        small = [row for row in table if row["size_class"] == "small"]
        self.assertTrue(small and all(row["batches"] == "1" and row["ci_low_default"] == "" for row in small))
        with open(os.path.join(out_dir, "table.md")) as stream:
            self.assertIn("| closed | cases | % hidden | IoU default", stream.read())
        bad = subprocess.run([sys.executable, PLOT_SCRIPT, os.path.join(self.folder, "nothing_here")],
                             capture_output=True, text=True, timeout=300, env=script_environment())
        self.assertEqual(bad.returncode, 2)
        self.assertIn("results.csv", bad.stderr)

    def test_bad_input_exits_2_with_a_clear_message(self):
        out_dir = os.path.join(self.folder, "bad")
        malformed = os.path.join(self.folder, "malformed.xml")
        with open(malformed, "w") as stream:
            stream.write("<building><scale>0.05</scale><floor>")
        cases = [
            (["--env", os.path.join(self.folder, "missing.xml")], "missing.xml: no such environment file"),
            (["--env", malformed], "malformed.xml"),
            (["--env", SMALL_WORLD, "--max-closed", "0"], "--max-closed must be at least 1"),
            (["--env", SMALL_WORLD, "--methods", "nope"], "unknown method(s) nope"),
            (["--env", SMALL_WORLD, "--batches", "0"], "--batches must be at least 1"),
        ]
        for arguments, message in cases:
            result = run_batch(*(arguments + ["--out", out_dir, "--binary", self.binary]))
            self.assertEqual(result.returncode, 2, "%s: %s" % (arguments, result.stdout + result.stderr))
            self.assertIn(message, result.stderr, arguments)
            self.assertFalse(os.path.isfile(os.path.join(out_dir, "results.csv")), arguments)

    def test_bad_parameters_name_the_users_file_and_leave_the_folder_resumable(self):
        out_dir = os.path.join(self.folder, "bad_params")
        params = os.path.join(self.folder, "params.yaml")
        with open(params, "w") as stream:
            stream.write("start_serach_radius: 2\n")
        arguments = ["--env", SMALL_WORLD, "--batches", "1", "--max-closed", "1", "--methods", "unstructured",
                     "--out", out_dir, "--binary", self.binary, "--params", params]
        result = run_batch(*arguments)
        self.assertEqual(result.returncode, 2, result.stdout + result.stderr)
        self.assertIn("%s: unknown parameter 'start_serach_radius'" % params, result.stderr)
        with open(params, "w") as stream:  # fixed: the same folder now runs
            stream.write("start_search_radius: 2\n")
        result = run_batch(*arguments)
        self.assertEqual(result.returncode, 0, result.stdout + result.stderr)

    def test_the_task_folders_of_killed_runs_are_removed(self):
        child = subprocess.Popen(["true"])
        child.wait()
        stale = os.path.join(tempfile.gettempdir(), "%s%d_abc" % (batch_analysis.TASK_FOLDER_PREFIX, child.pid))
        os.makedirs(stale, exist_ok=True)
        mine = tempfile.mkdtemp(prefix="%s%d_" % (batch_analysis.TASK_FOLDER_PREFIX, os.getpid()))
        batch_analysis.remove_stale_task_folders()
        self.assertFalse(os.path.exists(stale))
        self.assertTrue(os.path.isdir(mine))
        os.rmdir(mine)


class PlotBatchTest(unittest.TestCase):
    """plot_batch on a results.csv written by hand (no batch_cases needed): small has 3 batches, medium 1."""

    METHODS = ["default", "my_method"]
    # Per small batch, default's IoU in every case: batch means 0.4, 0.5, 0.6.
    SMALL_DEFAULT = {1: 0.4, 2: 0.5, 3: 0.6}

    @classmethod
    def setUpClass(cls):
        cls.folder = tempfile.mkdtemp(prefix="plot_batch_test_")
        cls.results_dir = os.path.join(cls.folder, "batch")
        os.makedirs(cls.results_dir)
        columns = batch_analysis.result_columns(cls.METHODS)
        with open(os.path.join(cls.results_dir, "results.csv"), "w", newline="") as stream:
            writer = csv.DictWriter(stream, fieldnames=columns, lineterminator="\n")
            writer.writeheader()
            for environment, size_class, batches in [("s1", "small", (1, 2, 3)), ("m1", "medium", (1,))]:
                for batch in batches:
                    for closed in (1, 2, 3):
                        row = {name: "0" for name in columns}
                        row.update(environment=environment, size_class=size_class, batch=str(batch),
                                   closed_doors=str(closed), hidden_percent=str(4.0 * closed),
                                   closed_door_ids=" ".join(map(str, range(1, closed + 1))), failed_methods="")
                        default = cls.SMALL_DEFAULT[batch] if size_class == "small" else 0.7
                        row.update(iou_default=str(default), iou_tot_default=str(default + 0.1),
                                   iou_my_method=str(0.3 + 0.05 * closed + 0.02 * batch),
                                   iou_tot_my_method=str(0.35 + 0.05 * closed))
                        writer.writerow(row)
        cls.out_dir = os.path.join(cls.folder, "plots")
        cls.result = run_plot(cls.results_dir, "--out", cls.out_dir)

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.folder, ignore_errors=True)

    def read_table(self):
        with open(os.path.join(self.out_dir, "table.csv"), newline="") as stream:
            return list(csv.DictReader(stream))

    def test_every_format_is_written(self):
        self.assertEqual(self.result.returncode, 0, self.result.stdout + self.result.stderr)
        check_figures(self, self.out_dir, PLOT_FORMATS)
        only_pdf = os.path.join(self.folder, "only_pdf")
        result = run_plot(self.results_dir, "--out", only_pdf, "--formats", "pdf")
        self.assertEqual(result.returncode, 0, result.stdout + result.stderr)
        check_figures(self, only_pdf, ["pdf"])
        self.assertFalse([name for name in os.listdir(only_pdf) if name.endswith((".png", ".svg"))])

    def test_confidence_intervals_over_batches(self):
        self.assertEqual(self.result.returncode, 0, self.result.stdout + self.result.stderr)
        table = self.read_table()
        for name in ("ci_low_default", "ci_high_default", "ci_low_tot_my_method", "ci_high_tot_my_method",
                     "batches"):
            self.assertIn(name, table[0])
        small = [row for row in table if row["size_class"] == "small"]
        medium = [row for row in table if row["size_class"] == "medium"]
        self.assertEqual([row["closed_doors"] for row in small], ["1", "2", "3", "all"])
        for row in small:
            self.assertEqual(row["batches"], "3")
            for method in self.METHODS:
                low, mean, high = (float(row[name + method]) for name in ("ci_low_", "iou_", "ci_high_"))
                self.assertTrue(all(map(math.isfinite, (low, mean, high))), row)
                self.assertTrue(low <= mean <= high, row)
            # Batch means 0.4, 0.5, 0.6: 0.5 +- t(0.975, 2 df) * 0.1 / sqrt(3).
            self.assertAlmostEqual(float(row["ci_low_default"]), 0.5 - 4.303 * 0.1 / math.sqrt(3), places=3)
            self.assertAlmostEqual(float(row["ci_high_default"]), 0.5 + 4.303 * 0.1 / math.sqrt(3), places=3)
        for row in medium:  # one batch: no interval
            self.assertEqual(row["batches"], "1")
            for method in self.METHODS:
                self.assertEqual((row["ci_low_" + method], row["ci_high_" + method]), ("", ""), row)
        with open(os.path.join(self.out_dir, "table.md")) as stream:
            markdown = stream.read()
        self.assertIn("| closed | cases | % hidden | IoU default", markdown)
        medium_part = markdown[markdown.index("## medium"):markdown.index("## all")]
        self.assertIn("**0.700** ± n/a", medium_part)
        self.assertNotIn("± 0.000", markdown)

    def test_latex_table(self):
        self.assertEqual(self.result.returncode, 0, self.result.stdout + self.result.stderr)
        with open(os.path.join(self.out_dir, "table.tex")) as stream:
            lines = stream.read().splitlines()
        body = [line for line in lines if not line.startswith("%")]
        text = "\n".join(body)
        for rule in ("\\toprule", "\\midrule", "\\bottomrule", "\\begin{tabular}", "\\end{tabular}"):
            self.assertIn(rule, text)
        self.assertIn("my\\_method", text)
        self.assertIn("hidden (\\%)", text)
        blocks = text.split("\\multicolumn")[1:]
        self.assertEqual([block.split("{\\textit{")[1].split(" ")[0] for block in blocks], ["small", "medium", "all"])
        for block in blocks:
            rows = [line for line in block.splitlines() if line.endswith("\\\\") and "&" in line]
            self.assertEqual([row.split(" & ")[0] for row in rows], ["1", "2", "3", "all"], block)
            self.assertTrue(all("\\textbf{" in row for row in rows), block)
            self.assertTrue(all(row.count("\\pm") == len(self.METHODS) for row in rows), block)
        self.assertIn("\\textbf{0.700} $\\pm$ n/a", blocks[1])
        unescaped = [line for line in body if "%" in line.replace("\\%", "")]
        self.assertEqual(unescaped, [])

    def test_bad_formats_exit_2_naming_the_format(self):
        out_dir = os.path.join(self.folder, "bad_formats")
        result = run_plot(self.results_dir, "--out", out_dir, "--formats", "png,jpeg")
        self.assertEqual(result.returncode, 2, result.stdout + result.stderr)
        self.assertIn("jpeg", result.stderr)
        self.assertIn("--formats", result.stderr)
        self.assertFalse(os.path.exists(out_dir))


class SharedEnvironmentTest(unittest.TestCase):
    """One short batch on a thesis environment of the shared data (skips when it is absent)."""

    def test_one_batch_on_a_shared_environment(self):
        shared = os.environ.get("HIDDEN_ROOMS_SHARED_DIR") or os.path.join(os.path.dirname(PACKAGE_DIR), "shared")
        environment = os.path.join(shared, "data", "environments", "school", "Sabadell1.xml")
        if not os.path.isfile(environment):
            if required():
                raise AssertionError("shared environment %s missing" % environment)
            raise unittest.SkipTest("shared data not found")
        binary = tool_or_skip()
        folder = tempfile.mkdtemp(prefix="batch_analysis_shared_")
        try:
            result = run_batch("--env", environment, "--batches", "1", "--max-closed", "3", "--out", folder,
                               "--binary", binary)
            self.assertEqual(result.returncode, 0, result.stdout + result.stderr)
            rows = keyed(read_rows(folder)[1])
            self.assertEqual(sorted(rows), [("Sabadell1", 1, k) for k in (1, 2, 3)])
            self.assertTrue(all(row["size_class"] == "medium" for row in rows.values()))  # 12 closable doors
        finally:
            shutil.rmtree(folder, ignore_errors=True)


if __name__ == "__main__":
    unittest.main()
