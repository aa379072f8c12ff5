"""Plots and tables of batch_analysis results (the thesis's Figures 6.13 to 6.17 and Table 6.4).

`plot_batch DIR [DIR...] [--out PLOT_DIR]` reads every DIR/results.csv and writes into PLOT_DIR (default
DIR/plots of the first DIR):
  iou_vs_closed_doors.png      mean IoU vs number of closed doors per method, mean and spread (one standard
                               deviation, clipped to [0, 1]), one panel per size class and one for all
  iou_tot_vs_closed_doors.png  the same for IoU_tot
  table.csv, table.md          per size class (and all) and number of closed doors: cases, mean % hidden, per
                               method mean IoU, its standard deviation and mean IoU_tot; a last row per class
                               over all its cases
  table.png                    the same tables as a picture (mean IoU)
"""
import csv
import os
import sys

import numpy as np

from hidden_rooms.batch_analysis import RESULTS_NAME, SIZE_CLASSES, methods_of
from hidden_rooms.package_tools import ArgumentParser

ALL = "all"


class PlotError(Exception):
    """Unusable input (exit code 2)."""


def read_results(folders):
    """(rows, methods): the rows of every folder's results.csv, and the methods in the order first seen."""
    rows, methods = [], []
    for folder in folders:
        path = os.path.join(folder, RESULTS_NAME)
        if not os.path.isfile(path):
            raise PlotError("%s: no %s (not a batch_analysis output folder)" % (folder, RESULTS_NAME))
        with open(path, newline="") as stream:
            reader = csv.DictReader(stream)
            columns = reader.fieldnames or []
            missing = {"environment", "size_class", "batch", "closed_doors", "hidden_percent"} - set(columns)
            if missing:
                raise PlotError("%s lacks the column(s) %s" % (path, ", ".join(sorted(missing))))
            folder_methods = methods_of(columns)
            methods += [method for method in folder_methods if method not in methods]
            for line, row in enumerate(reader, start=2):
                try:
                    parsed = {"size_class": row["size_class"], "environment": row["environment"],
                              "closed_doors": int(row["closed_doors"]),
                              "hidden_percent": float(row["hidden_percent"])}
                    for method in folder_methods:
                        parsed["iou_" + method] = float(row["iou_" + method])
                        parsed["iou_tot_" + method] = float(row["iou_tot_" + method])
                except (TypeError, ValueError) as error:
                    raise PlotError("%s:%d: bad row: %s" % (path, line, error))
                rows.append(parsed)
    if not rows:
        raise PlotError("no rows in %s" % ", ".join(os.path.join(folder, RESULTS_NAME) for folder in folders))
    return rows, methods


def groups(rows):
    """[(class name, rows)] for each size class present, then all."""
    present = [name for name in SIZE_CLASSES if any(row["size_class"] == name for row in rows)]
    present += sorted({row["size_class"] for row in rows} - set(SIZE_CLASSES))
    result = [(name, [row for row in rows if row["size_class"] == name]) for name in present]
    if len(present) > 1:
        result.append((ALL, rows))
    return result


def statistics(rows, methods):
    """Table rows per number of closed doors, then one over all rows ('all')."""
    table = []
    counts = sorted({row["closed_doors"] for row in rows})
    for closed in counts + [ALL]:
        selected = rows if closed == ALL else [row for row in rows if row["closed_doors"] == closed]
        entry = {"closed_doors": closed, "cases": len(selected),
                 "hidden_percent": float(np.mean([row["hidden_percent"] for row in selected]))}
        for method in methods:
            values = [row["iou_" + method] for row in selected if "iou_" + method in row]
            totals = [row["iou_tot_" + method] for row in selected if "iou_tot_" + method in row]
            entry["iou_" + method] = float(np.mean(values)) if values else float("nan")
            entry["iou_std_" + method] = float(np.std(values)) if values else float("nan")
            entry["iou_tot_" + method] = float(np.mean(totals)) if totals else float("nan")
        table.append(entry)
    return table


def table_columns(methods):
    return (["size_class", "closed_doors", "cases", "hidden_percent"] + ["iou_" + m for m in methods] +
            ["iou_std_" + m for m in methods] + ["iou_tot_" + m for m in methods])


def write_tables(out_dir, tables, methods, environments):
    """table.csv and table.md."""
    with open(os.path.join(out_dir, "table.csv"), "w", newline="") as stream:
        writer = csv.DictWriter(stream, fieldnames=table_columns(methods), lineterminator="\n")
        writer.writeheader()
        for name, table in tables:
            for entry in table:
                row = {"size_class": name}
                for key, value in entry.items():
                    row[key] = "%.4f" % value if isinstance(value, float) else value
                writer.writerow(row)
    with open(os.path.join(out_dir, "table.md"), "w") as stream:
        stream.write("# Batch analysis: mean IoU by number of closed doors\n\n")
        for name, table in tables:
            stream.write("## %s (%d environments, %d cases)\n\n" % (name, environments[name], table[-1]["cases"]))
            stream.write("| closed | cases | % hidden | " + " | ".join("IoU %s" % m for m in methods) + " | " +
                         " | ".join("IoU_tot %s" % m for m in methods) + " |\n")
            stream.write("|" + "---|" * (3 + 2 * len(methods)) + "\n")
            for entry in table:
                closed = "**all**" if entry["closed_doors"] == ALL else str(entry["closed_doors"])
                stream.write("| %s | %d | %.2f | " % (closed, entry["cases"], entry["hidden_percent"]) +
                             " | ".join("%.3f ± %.3f" % (entry["iou_" + m], entry["iou_std_" + m]) for m in methods) +
                             " | " + " | ".join("%.3f" % entry["iou_tot_" + m] for m in methods) + " |\n")
            stream.write("\n")


def plot_curves(path, tables, methods, key, label):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    figure, axes = plt.subplots(1, len(tables), figsize=(5.0 * len(tables), 4.2), squeeze=False, sharey=True)
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for axis, (name, table) in zip(axes[0], tables):
        entries = [entry for entry in table if entry["closed_doors"] != ALL]
        closed = [entry["closed_doors"] for entry in entries]
        for index, method in enumerate(methods):
            colour = colours[index % len(colours)]
            mean = np.array([entry[key + method] for entry in entries])
            axis.plot(closed, mean, marker="o", markersize=3, color=colour, label=method)
            if key == "iou_":
                spread = np.array([entry["iou_std_" + method] for entry in entries])
                axis.fill_between(closed, np.clip(mean - spread, 0, 1), np.clip(mean + spread, 0, 1), color=colour,
                                  alpha=0.12, linewidth=0)
        axis.set_title("%s (%d cases)" % (name, table[-1]["cases"]))
        axis.set_xlabel("closed doors")
        axis.set_ylim(0, 1)
        axis.grid(alpha=0.3)
        if closed:
            axis.set_xticks(range(1, max(closed) + 1))
    axes[0][0].set_ylabel(label)
    axes[0][0].legend(loc="lower left", fontsize="small")
    figure.tight_layout()
    figure.savefig(path, dpi=110)
    plt.close(figure)


def plot_table(path, tables, methods):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    heights = [0.6 + 0.24 * (len(table) + 1) for _, table in tables]
    figure, axes = plt.subplots(len(tables), 1, figsize=(2.0 + 1.2 * len(methods), sum(heights)), squeeze=False,
                                gridspec_kw={"height_ratios": heights})
    for axis, (name, table) in zip(axes[:, 0], tables):
        axis.axis("off")
        cells = [["all" if e["closed_doors"] == ALL else str(e["closed_doors"]), str(e["cases"]),
                  "%.2f" % e["hidden_percent"]] + ["%.3f" % e["iou_" + m] for m in methods] for e in table]
        best = [int(np.nanargmax([e["iou_" + m] for m in methods])) for e in table]
        drawn = axis.table(cellText=cells, colLabels=["closed", "cases", "% hidden"] + methods, loc="upper center",
                           cellLoc="center")
        drawn.auto_set_font_size(False)
        drawn.set_fontsize(8)
        for row, column in enumerate(best, start=1):
            drawn[row, 3 + column].set_text_props(fontweight="bold")
        axis.set_title("mean IoU, %s" % name, fontsize=9)
    figure.tight_layout()
    figure.savefig(path, dpi=110)
    plt.close(figure)


def main(argv=None):
    parser = ArgumentParser(prog="plot_batch", description="Plots and tables of batch_analysis results.")
    parser.add_argument("folders", nargs="+", metavar="DIR", help="batch_analysis output folder(s)")
    parser.add_argument("--out", help="folder for the plots and tables (default: DIR/plots of the first DIR)")
    args = parser.parse_args(sys.argv[1:] if argv is None else argv)
    try:
        rows, methods = read_results(args.folders)
    except PlotError as error:
        print("plot_batch: error: %s" % error, file=sys.stderr)
        return 2
    out_dir = args.out or os.path.join(args.folders[0], "plots")
    os.makedirs(out_dir, exist_ok=True)
    grouped = groups(rows)
    tables = [(name, statistics(selected, methods)) for name, selected in grouped]
    environments = {name: len({row["environment"] for row in selected}) for name, selected in grouped}
    write_tables(out_dir, tables, methods, environments)
    plot_curves(os.path.join(out_dir, "iou_vs_closed_doors.png"), tables, methods, "iou_", "mean IoU")
    plot_curves(os.path.join(out_dir, "iou_tot_vs_closed_doors.png"), tables, methods, "iou_tot_", "IoU_tot")
    plot_table(os.path.join(out_dir, "table.png"), tables, methods)
    print("plot_batch: %d rows, %d environments, methods %s -> %s (iou_vs_closed_doors.png, "
          "iou_tot_vs_closed_doors.png, table.png, table.csv, table.md)" % (
              len(rows), environments[grouped[-1][0]], ",".join(methods), out_dir))
    return 0
