#!/usr/bin/python3
"""scripts/benchmark_closed_doors.py on a small benchmark made of a few cases of the shared closed-door benchmark.

The shared data folder is $HIDDEN_ROOMS_SHARED_DIR or ../shared beside the checkout; tests that need it (or the
built predict_rooms_offline) skip when it is absent, unless HIDDEN_ROOMS_REQUIRE_SHARED=1, when they fail.
"""
import csv
import importlib.util
import os
import re
import shutil
import subprocess
import sys
import tempfile
import unittest

import cv2
import numpy as np

PACKAGE_DIR = os.path.dirname(os.path.dirname(os.path.dirname(os.path.realpath(__file__))))
SCRIPT = os.path.join(PACKAGE_DIR, "scripts", "benchmark_closed_doors.py")
# (env, case) copied into the small benchmark: one case with 1 door, two with 2 doors.
SELECTED_CASES = [("office1_fs", "01_doors"), ("office1_fs", "02_doors"), ("Sabadell1", "02_doors")]
TABLE_ROW = re.compile(r"^\s*(\d+)\s+(\d+)\s")


def load_script_module():
    """The benchmark script imported as a module (its name has no package)."""
    spec = importlib.util.spec_from_file_location("benchmark_closed_doors", SCRIPT)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def shared_required():
    return os.environ.get("HIDDEN_ROOMS_REQUIRE_SHARED") == "1"


def shared_benchmark_dir():
    """The shared closed-door benchmark folder, None when absent."""
    shared = os.environ.get("HIDDEN_ROOMS_SHARED_DIR") or os.path.join(os.path.dirname(PACKAGE_DIR), "shared")
    folder = os.path.join(shared, "data", "closed_door_benchmark")
    return folder if os.path.isfile(os.path.join(folder, "cases.csv")) else None


def run_script(*arguments):
    """Runs the script; returns the CompletedProcess with text stdout and stderr."""
    return subprocess.run([sys.executable, SCRIPT] + list(arguments), capture_output=True, text=True, timeout=600)


def read_table(stdout):
    """{doors: cases} from the printed table by number of closed doors."""
    rows = {}
    lines = stdout.splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith("doors  cases")) + 2
    for line in lines[start:]:
        match = TABLE_ROW.match(line)
        if not match:
            break
        rows[int(match.group(1))] = int(match.group(2))
    return rows


class DoorIou(unittest.TestCase):
    """The reference score's IoU per label, on tiny label images (no data needed)."""

    def test_iou_per_label(self):
        module = load_script_module()
        truth = np.array([[1, 1, 0, 2], [1, 1, 0, 2]], dtype=np.uint8)
        predicted = np.array([[1, 0, 0, 0], [1, 0, 3, 0]], dtype=np.uint8)
        ious = module.door_ious(predicted, truth, 3)
        self.assertAlmostEqual(ious[0], 0.5)  # 2 of 4 pixels, nothing extra
        self.assertEqual(ious[1], 0.0)  # no prediction
        self.assertEqual(ious[2], 0.0)  # predicted but no true room
        # --agreement counts two empty rooms as agreeing.
        self.assertEqual(module.door_ious(predicted, truth, 4, both_empty=1.0)[3], 1.0)
        self.assertEqual(module.door_ious(predicted, truth, 4, both_empty=1.0)[1], 0.0)


class BadBenchmarkFolder(unittest.TestCase):
    def test_missing_cases_csv_exits_2(self):
        folder = tempfile.mkdtemp(prefix="bench_empty_")
        try:
            result = run_script(folder, "--method", "unstructured")
        finally:
            shutil.rmtree(folder)
        self.assertEqual(result.returncode, 2, result.stdout + result.stderr)
        self.assertIn("cases.csv", result.stderr)

    def test_no_method_exits_2(self):
        self.assertEqual(run_script("/nonexistent").returncode, 2)


class SmallBenchmark(unittest.TestCase):
    """The script on a copy of a few shared cases, with the built predict_rooms_offline."""

    @classmethod
    def setUpClass(cls):
        cls.folder = None
        source = shared_benchmark_dir()
        if source is None:
            if shared_required():
                raise AssertionError("shared closed-door benchmark missing (HIDDEN_ROOMS_REQUIRE_SHARED=1)")
            raise unittest.SkipTest("shared closed-door benchmark not found")
        module = load_script_module()
        try:
            cls.binary = module.find_binary()
        except module.BenchmarkError as error:
            if shared_required():
                raise AssertionError("predict_rooms_offline not built: %s" % error)
            raise unittest.SkipTest("predict_rooms_offline not built: %s" % error)
        methods = module.known_methods(cls.binary) or ["unstructured"]
        cls.method = "unstructured" if "unstructured" in methods else methods[0]

        cls.folder = tempfile.mkdtemp(prefix="bench_small_")
        with open(os.path.join(source, "cases.csv"), newline="") as stream:
            reader = csv.DictReader(stream)
            cls.fields = reader.fieldnames
            cls.rows = [row for row in reader if (row["env"], row["case"]) in SELECTED_CASES]
        assert len(cls.rows) == len(SELECTED_CASES), "selected cases missing from the shared cases.csv"
        for row in cls.rows:
            shutil.copytree(os.path.join(source, row["env"], row["case"]),
                            os.path.join(cls.folder, row["env"], row["case"]))
        cls.write_cases(cls.folder, cls.rows)

    @classmethod
    def tearDownClass(cls):
        if cls.folder:
            shutil.rmtree(cls.folder, ignore_errors=True)

    @classmethod
    def write_cases(cls, folder, rows):
        with open(os.path.join(folder, "cases.csv"), "w", newline="") as stream:
            writer = csv.DictWriter(stream, fieldnames=cls.fields)
            writer.writeheader()
            writer.writerows(rows)

    def test_table_and_reference_scores(self):
        csv_path = os.path.join(self.folder, "per_case.csv")
        result = run_script(self.folder, "--method", self.method, "--jobs", "2", "--binary", self.binary,
                            "--csv", csv_path)
        self.assertEqual(result.returncode, 0, result.stdout + result.stderr)

        table = read_table(result.stdout)
        self.assertEqual(sorted(table), list(range(1, 16)))
        self.assertEqual(table[1], 1)
        self.assertEqual(table[2], 2)
        self.assertTrue(all(table[doors] == 0 for doors in range(3, 16)))

        with open(csv_path, newline="") as stream:
            per_case = list(csv.DictReader(stream))
        self.assertEqual(len(per_case), len(SELECTED_CASES))
        expected = {(row["env"], row["case"]): float(row["reference_iou"]) for row in self.rows}
        for row in per_case:
            self.assertEqual(row["method"], self.method)
            self.assertEqual(row["status"], "ok")
            self.assertGreaterEqual(float(row["mean_iou"]), 0.0)
            self.assertLessEqual(float(row["mean_iou"]), 1.0)
            self.assertGreater(float(row["seconds"]), 0.0)
            self.assertAlmostEqual(float(row["reference_iou"]), expected[(row["env"], row["case"])], delta=0.01)

        overall = re.search(r"reference\s+mean IoU\s+([0-9.]+) over (\d+) cases", result.stdout)
        self.assertIsNotNone(overall, result.stdout)
        self.assertEqual(int(overall.group(2)), len(SELECTED_CASES))
        self.assertAlmostEqual(float(overall.group(1)), np.mean(list(expected.values())), delta=0.01)

    def test_turned_cases_are_the_cases_turned(self):
        """--turn: a quarter turn moves every cell exactly and swaps the doors' orientations; a run with a small turn
        reports its turn and no reference scores."""
        module = load_script_module()
        case = module.load_cases(self.folder)[0]
        root = tempfile.mkdtemp(prefix="bench_turned_")
        quarter = module.turned_case(case, 90.0, root)
        truth = module.read_label_image(case.path("gt_rooms.png"))
        turned_truth = module.read_label_image(quarter.path("gt_rooms.png"))
        np.testing.assert_array_equal(turned_truth, np.rot90(truth))
        import yaml
        with open(case.path("doors.yaml")) as a, open(quarter.path("doors.yaml")) as b:
            straight_doors, turned_doors = yaml.safe_load(a)["doors"], yaml.safe_load(b)["doors"]
        for straight, turned in zip(straight_doors, turned_doors):
            self.assertNotEqual(straight["orientation"], turned["orientation"])
        # A small turn keeps the margin the map has around its building on each side.
        small = module.turned_case(case, 3.0, root)
        with open(case.path("map.yaml")) as stream:
            image = cv2.imread(case.path(yaml.safe_load(stream)["image"]), cv2.IMREAD_UNCHANGED)
        turned_image = cv2.imread(small.path("map.png"), cv2.IMREAD_UNCHANGED)
        np.testing.assert_array_equal(module.content_margins(turned_image, module.read_label_image(
            small.path("gt_rooms.png")), 205), module.content_margins(image, truth, 205))
        result = run_script(self.folder, "--method", self.method, "--jobs", "2", "--binary", self.binary,
                            "--turn", "3")
        self.assertEqual(result.returncode, 0, result.stdout + result.stderr)
        self.assertIn("turned by 3 degrees", result.stdout)
        self.assertNotIn("nan", result.stdout)
        self.assertEqual(run_script(self.folder, "--method", self.method, "--turn", "3", "--agreement").returncode, 2)
        shutil.rmtree(root, ignore_errors=True)

    def test_agreement_with_the_truth_as_reference(self):
        """With reference_rooms.png replaced by gt_rooms.png, a method's room-by-room agreement with the reference
        is its IoU against the truth, case by case."""
        folder = tempfile.mkdtemp(prefix="bench_agreement_")
        try:
            for row in self.rows:
                case_dir = os.path.join(folder, row["env"], row["case"])
                shutil.copytree(os.path.join(self.folder, row["env"], row["case"]), case_dir)
                shutil.copyfile(os.path.join(case_dir, "gt_rooms.png"), os.path.join(case_dir, "reference_rooms.png"))
            self.write_cases(folder, self.rows)
            result = run_script(folder, "--method", self.method, "--binary", self.binary, "--agreement")
        finally:
            shutil.rmtree(folder, ignore_errors=True)
        self.assertEqual(result.returncode, 0, result.stdout + result.stderr)
        lines = {}
        for line in result.stdout.splitlines():
            fields = line.split()
            if len(fields) == 5 and "/" in fields[0] and fields[1].isdigit():
                lines[fields[0]] = [float(value) for value in fields[2:]]
        self.assertEqual(sorted(lines), sorted("%s/%s" % (row["env"], row["case"]) for row in self.rows))
        for label, (agreement, iou, reference_iou) in lines.items():
            self.assertAlmostEqual(agreement, iou, delta=1e-3, msg=label)
            self.assertAlmostEqual(reference_iou, 1.0, msg=label)
        self.assertRegex(result.stdout, r"%s: agreement mean [0-9.]+, median [0-9.]+ over 5 rooms" % self.method)

    def test_variants_and_the_best_column_per_door(self):
        """--variant adds a column of a method with its own parameters; --best-of takes per door the best column's
        IoU, so it is at least every column's mean, and a variant that repeats a column changes nothing."""
        folder = tempfile.mkdtemp(prefix="bench_variants_")
        try:
            same, grown = os.path.join(folder, "same.yaml"), os.path.join(folder, "grown.yaml")
            with open(same, "w") as stream:
                stream.write("default_network: 3\n")
            with open(grown, "w") as stream:
                stream.write("default_network: 0\ndefault_grown_area_ratio: 0\n")
            common = [self.folder, "--binary", self.binary, "--jobs", "2", "--best-of"]
            result = run_script(*common, "--method", "default", "--variant", "grown", "default", grown)
            repeated = run_script(*common, "--method", "default", "--variant", "again", "default", same)
            errors = [run_script(*common, "--method", "default"),
                      run_script(*common, "--method", "default", "--variant", "default", "default", same),
                      run_script(*common, "--method", "default", "--variant", "grown", "default",
                                 os.path.join(folder, "missing.yaml"))]
        finally:
            shutil.rmtree(folder, ignore_errors=True)
        self.assertEqual(result.returncode, 0, result.stdout + result.stderr)
        self.assertEqual(repeated.returncode, 0, repeated.stdout + repeated.stderr)
        for error in errors:
            self.assertEqual(error.returncode, 2, error.stdout + error.stderr)

        def best_of_row(stdout):
            match = re.search(r"^all\s+(\d+)\s+([0-9.]+)\s+([0-9.]+)\s+([0-9.]+)$", stdout, re.MULTILINE)
            self.assertIsNotNone(match, stdout)
            return int(match.group(1)), [float(match.group(k)) for k in (2, 3, 4)]

        cases, (method, variant, best) = best_of_row(result.stdout)
        self.assertEqual(cases, len(SELECTED_CASES))
        self.assertNotEqual(method, variant)  # the variant's parameters reached its runs
        self.assertGreaterEqual(best, max(method, variant))
        self.assertLessEqual(best, 1.0)
        _, (method_again, variant_again, best_again) = best_of_row(repeated.stdout)
        self.assertEqual(method_again, method)
        self.assertEqual(variant_again, method)
        self.assertEqual(best_again, method)

    def test_failed_case_is_reported_and_others_continue(self):
        folder = tempfile.mkdtemp(prefix="bench_broken_")
        try:
            good = dict(self.rows[0])
            broken = dict(self.rows[1], case="99_broken")
            shutil.copytree(os.path.join(self.folder, good["env"], good["case"]),
                            os.path.join(folder, good["env"], good["case"]))
            broken_dir = os.path.join(folder, broken["env"], broken["case"])
            shutil.copytree(os.path.join(self.folder, self.rows[1]["env"], self.rows[1]["case"]), broken_dir)
            with open(os.path.join(broken_dir, "map.yaml"), "w") as stream:
                stream.write("image: missing.png\nresolution: 0.05\norigin: [0, 0, 0]\n")
            self.write_cases(folder, [good, broken])
            csv_path = os.path.join(folder, "per_case.csv")
            result = run_script(folder, "--method", self.method, "--binary", self.binary, "--csv", csv_path)
            with open(csv_path, newline="") as stream:
                status = {row["case"]: row for row in csv.DictReader(stream)}
        finally:
            shutil.rmtree(folder, ignore_errors=True)
        self.assertEqual(result.returncode, 1, result.stdout + result.stderr)
        self.assertIn("1 failed run(s)", result.stdout)
        self.assertIn("99_broken", result.stdout)
        self.assertEqual(status["99_broken"]["status"], "failed")
        self.assertEqual(float(status["99_broken"]["mean_iou"]), 0.0)
        self.assertEqual(status[good["case"]]["status"], "ok")


if __name__ == "__main__":
    unittest.main()
