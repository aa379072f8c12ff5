"""Plots and tables of batch_analysis results (the thesis's Figures 6.13 to 6.17 and Table 6.4).

`plot_batch DIR [DIR...] [--out PLOT_DIR] [--formats png,pdf,svg]` reads every DIR/results.csv and writes into
PLOT_DIR (default DIR/plots of the first DIR), each figure once per format of --formats (default all three; PNG at
200 dpi, PDF with TrueType fonts, SVG):
  iou_vs_closed_doors.*      mean IoU of the hidden rooms against the number of closed doors, one curve per method,
                             one panel per size class and one for all
  iou_tot_vs_closed_doors.*  the same for IoU_tot (all predicted rooms together against all hidden rooms
                             together)
  iou_by_size_class.*        mean IoU against the number of closed doors, one panel per method, one curve per size
                             class
  table.*                    the table's mean IoU as a picture (best method in bold)
  table.csv, table.md        per size class (and all) and number of closed doors: cases, mean % hidden, per
                             method mean IoU with its 95 % confidence interval, the standard deviation over the
                             cases and mean IoU_tot; a last row per class over all its cases. table.csv also has
                             the batches and the interval of IoU_tot
  table.tex                  the mean IoU table as a LaTeX tabular (booktabs rules, one block per size class, best
                             method per row in bold)

Confidence intervals: the cases of a cell (size class, closed doors) are grouped by their `batch` column (batch b
of every environment and folder is one group), each batch's mean is one sample, and the interval is
mean +- t * s / sqrt(n): n batches, s the standard deviation of the batch means, t Student's 97.5 % quantile with
n - 1 degrees of freedom (scipy.stats.t). The mean is that over the cases (the batch means' mean when the batches
have equal numbers of cases). With fewer than 2 batches there is no interval: no band, empty CSV cells, "n/a" in
table.md and table.tex. Bands are clipped to [0, 1]; the tables are not.
"""
import csv
import math
import os
import sys

import numpy as np
from scipy.stats import t as student_t

from hidden_rooms.batch_analysis import RESULTS_NAME, SIZE_CLASSES, methods_of
from hidden_rooms.package_tools import ArgumentParser

ALL = "all"
FORMATS = ["png", "pdf", "svg"]
PNG_DPI = 200
CONFIDENCE = 0.95
X_LABEL = "number of closed doors"
IOU_LABEL = "mean IoU of the hidden rooms"
IOU_TOT_LABEL = "mean IoU of all hidden rooms together (IoU_tot)"
BAND_LABEL = "95 % confidence interval over batches"
LATEX_SPECIAL = {"\\": r"\textbackslash{}", "&": r"\&", "%": r"\%", "$": r"\$", "#": r"\#", "_": r"\_",
                 "{": r"\{", "}": r"\}", "~": r"\textasciitilde{}", "^": r"\textasciicircum{}"}


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
                              "batch": int(row["batch"]), "closed_doors": int(row["closed_doors"]),
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


def confidence_interval(rows, key):
    """(low, high): the 95 % confidence interval of the mean of `key` over the rows, the per-batch means being the
    samples, centred on the mean over the rows; (nan, nan) with fewer than 2 batches."""
    by_batch = {}
    for row in rows:
        if key in row:
            by_batch.setdefault(row["batch"], []).append(row[key])
    if len(by_batch) < 2:
        return float("nan"), float("nan")
    samples = np.array([np.mean(values) for values in by_batch.values()])
    t_quantile = student_t.ppf(0.5 + CONFIDENCE / 2, len(samples) - 1)
    half_width = t_quantile * samples.std(ddof=1) / math.sqrt(len(samples))
    mean = float(np.mean([row[key] for row in rows if key in row]))
    return mean - half_width, mean + half_width


def statistics(rows, methods):
    """Table rows per number of closed doors, then one over all rows ('all')."""
    table = []
    counts = sorted({row["closed_doors"] for row in rows})
    for closed in counts + [ALL]:
        selected = rows if closed == ALL else [row for row in rows if row["closed_doors"] == closed]
        entry = {"closed_doors": closed, "cases": len(selected), "batches": len({row["batch"] for row in selected}),
                 "hidden_percent": float(np.mean([row["hidden_percent"] for row in selected]))}
        for method in methods:
            values = [row["iou_" + method] for row in selected if "iou_" + method in row]
            totals = [row["iou_tot_" + method] for row in selected if "iou_tot_" + method in row]
            entry["iou_" + method] = float(np.mean(values)) if values else float("nan")
            entry["iou_std_" + method] = float(np.std(values)) if values else float("nan")
            entry["iou_tot_" + method] = float(np.mean(totals)) if totals else float("nan")
            entry["ci_low_" + method], entry["ci_high_" + method] = confidence_interval(selected, "iou_" + method)
            entry["ci_low_tot_" + method], entry["ci_high_tot_" + method] = confidence_interval(
                selected, "iou_tot_" + method)
        table.append(entry)
    return table


def table_columns(methods):
    return (["size_class", "closed_doors", "cases", "hidden_percent"] + ["iou_" + m for m in methods] +
            ["iou_std_" + m for m in methods] + ["iou_tot_" + m for m in methods] + ["batches"] +
            ["ci_low_" + m for m in methods] + ["ci_high_" + m for m in methods] +
            ["ci_low_tot_" + m for m in methods] + ["ci_high_tot_" + m for m in methods])


def half_width_text(entry, method, number_format):
    """The interval's half-width, or "n/a" without an interval."""
    low, high = entry["ci_low_" + method], entry["ci_high_" + method]
    return "n/a" if math.isnan(low) else number_format % ((high - low) / 2)


def best_methods(entry, methods):
    """The methods whose mean IoU, rounded to the tables' 3 decimals, is the row's highest."""
    rounded = {method: round(entry["iou_" + method], 3) for method in methods
               if not math.isnan(entry["iou_" + method])}
    return {method for method, value in rounded.items() if value == max(rounded.values())}


def class_title(name, table, environments):
    total = table[-1]
    return "%s (%d environment%s, %d cases, %d batch%s)" % (
        name, environments[name], "" if environments[name] == 1 else "s", total["cases"], total["batches"],
        "" if total["batches"] == 1 else "es")


def write_csv_table(path, tables, methods):
    with open(path, "w", newline="") as stream:
        writer = csv.DictWriter(stream, fieldnames=table_columns(methods), lineterminator="\n")
        writer.writeheader()
        for name, table in tables:
            for entry in table:
                row = {"size_class": name}
                for key, value in entry.items():
                    if isinstance(value, float):
                        row[key] = "" if math.isnan(value) else "%.4f" % value
                    else:
                        row[key] = value
                writer.writerow(row)


def write_markdown_table(path, tables, methods, environments):
    with open(path, "w") as stream:
        stream.write("# Batch analysis: mean IoU by number of closed doors\n\n"
                     "IoU: mean IoU of the hidden rooms ± the half-width of its 95 % confidence interval over "
                     "batches (n/a with fewer than 2 batches). IoU_tot: mean IoU of all hidden rooms together.\n\n")
        for name, table in tables:
            stream.write("## %s\n\n" % class_title(name, table, environments))
            stream.write("| closed | cases | % hidden | " + " | ".join("IoU %s" % m for m in methods) + " | " +
                         " | ".join("IoU_tot %s" % m for m in methods) + " |\n")
            stream.write("|" + "---|" * (3 + 2 * len(methods)) + "\n")
            for entry in table:
                closed = "**all**" if entry["closed_doors"] == ALL else str(entry["closed_doors"])
                cells = iou_cells(entry, methods, "**%s**", "±")
                stream.write("| %s | %d | %.2f | " % (closed, entry["cases"], entry["hidden_percent"]) +
                             " | ".join(cells) + " | " +
                             " | ".join("%.3f" % entry["iou_tot_" + m] for m in methods) + " |\n")
            stream.write("\n")


def iou_cells(entry, methods, bold, plus_minus):
    """Per method, "mean PLUS_MINUS half-width" of the table entry's IoU, the best methods' mean formatted by `bold`."""
    best = best_methods(entry, methods)
    cells = []
    for m in methods:
        mean = "%.3f" % entry["iou_" + m]
        cells.append("%s %s %s" % (bold % mean if m in best else mean, plus_minus, half_width_text(entry, m, "%.3f")))
    return cells


def latex_escape(text):
    return "".join(LATEX_SPECIAL.get(character, character) for character in str(text))


def write_latex_table(path, tables, methods, environments):
    """A booktabs tabular of the mean IoU ± the half-width of its 95 % interval, one block per size class."""
    columns = 3 + len(methods)
    lines = ["% plot_batch: mean IoU of the hidden rooms $\\pm$ the half-width of its 95\\,\\% confidence "
             "interval over batches (n/a: fewer than 2 batches); best method per row in bold.",
             "% Needs \\usepackage{booktabs}.",
             "\\begin{tabular}{rrr%s}" % ("c" * len(methods)),
             "\\toprule",
             "closed doors & cases & hidden (\\%) & " + " & ".join(latex_escape(m) for m in methods) + " \\\\"]
    for name, table in tables:
        lines += ["\\midrule",
                  "\\multicolumn{%d}{l}{\\textit{%s}} \\\\" % (columns, latex_escape(class_title(name, table,
                                                                                                   environments)))]
        for entry in table:
            if entry["closed_doors"] == ALL:
                lines.append("\\addlinespace[2pt]")
            cells = iou_cells(entry, methods, "\\textbf{%s}", "$\\pm$")
            lines.append("%s & %d & %.1f & %s \\\\" % (entry["closed_doors"], entry["cases"], entry["hidden_percent"],
                                                      " & ".join(cells)))
    lines += ["\\bottomrule", "\\end{tabular}"]
    with open(path, "w") as stream:
        stream.write("\n".join(lines) + "\n")


def write_tables(out_dir, tables, methods, environments):
    """table.csv, table.md and table.tex."""
    write_csv_table(os.path.join(out_dir, "table.csv"), tables, methods)
    write_markdown_table(os.path.join(out_dir, "table.md"), tables, methods, environments)
    write_latex_table(os.path.join(out_dir, "table.tex"), tables, methods, environments)


def pyplot():
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


def save_figure(figure, stem, formats):
    """STEM.FORMAT for each format (TrueType fonts in the PDF, as publishers ask); the paths written."""
    import matplotlib
    paths = []
    with matplotlib.rc_context({"pdf.fonttype": 42, "ps.fonttype": 42}):
        for extension in formats:
            paths.append("%s.%s" % (stem, extension))
            figure.savefig(paths[-1], dpi=PNG_DPI, format=extension)
    return paths


def draw_curve(axis, entries, key, ci_key, colour, label, **style):
    """One mean curve against the closed doors, with its interval as a band where there is one."""
    closed = [entry["closed_doors"] for entry in entries]
    mean = np.array([entry[key] for entry in entries])
    axis.plot(closed, mean, marker="o", markersize=3, color=colour, label=label, **style)
    low = np.array([entry["ci_low_" + ci_key] for entry in entries])
    high = np.array([entry["ci_high_" + ci_key] for entry in entries])
    has_interval = ~np.isnan(low)
    if has_interval.any():
        axis.fill_between(closed, np.clip(low, 0, 1), np.clip(high, 0, 1), where=has_interval, color=colour,
                          alpha=0.15, linewidth=0)
    return bool(has_interval.any())


def finish_panels(figure, axes, y_label, banded, legend_title=None):
    for axis in axes:
        axis.set_xlabel(X_LABEL)
        axis.set_ylim(0, 1)
        axis.grid(alpha=0.3)
        ticks = [int(x) for line in axis.get_lines() for x in line.get_xdata()]
        if ticks:
            axis.set_xticks(range(1, max(ticks) + 1))
    axes[0].set_ylabel(y_label)
    handles, labels = axes[0].get_legend_handles_labels()
    if banded:
        from matplotlib.patches import Patch
        handles.append(Patch(color="grey", alpha=0.3, linewidth=0))
        labels.append(BAND_LABEL)
    axes[0].legend(handles, labels, loc="lower left", fontsize="small", title=legend_title,
                   title_fontsize="small")
    figure.tight_layout()


def plot_by_size_class_panels(stem, tables, methods, key, label, environments, formats):
    """One panel per size class (and all), one curve per method."""
    plt = pyplot()
    figure, axes = plt.subplots(1, len(tables), figsize=(5.0 * len(tables), 4.2), squeeze=False, sharey=True)
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    ci_prefix = "tot_" if key == "iou_tot_" else ""
    banded = False
    for axis, (name, table) in zip(axes[0], tables):
        entries = [entry for entry in table if entry["closed_doors"] != ALL]
        for index, method in enumerate(methods):
            banded |= draw_curve(axis, entries, key + method, ci_prefix + method, colours[index % len(colours)],
                                 method)
        axis.set_title(class_title(name, table, environments), fontsize="medium")
    finish_panels(figure, axes[0], label, banded)
    paths = save_figure(figure, stem, formats)
    plt.close(figure)
    return paths


def plot_by_method_panels(stem, tables, methods, formats):
    """One panel per method, one curve per size class (the overall 'all' is left out)."""
    plt = pyplot()
    classes = [(name, table) for name, table in tables if name != ALL]
    figure, axes = plt.subplots(1, len(methods), figsize=(4.2 * len(methods), 4.2), squeeze=False, sharey=True)
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    banded = False
    for axis, method in zip(axes[0], methods):
        for index, (name, table) in enumerate(classes):
            entries = [entry for entry in table if entry["closed_doors"] != ALL]
            banded |= draw_curve(axis, entries, "iou_" + method, method, colours[index % len(colours)], name)
        axis.set_title(method, fontsize="medium")
    finish_panels(figure, axes[0], IOU_LABEL, banded, legend_title="size class")
    paths = save_figure(figure, stem, formats)
    plt.close(figure)
    return paths


def plot_table(stem, tables, methods, formats):
    plt = pyplot()
    heights = [0.6 + 0.24 * (len(table) + 1) for _, table in tables]
    figure, axes = plt.subplots(len(tables), 1, figsize=(2.0 + 1.2 * len(methods), sum(heights)), squeeze=False,
                                gridspec_kw={"height_ratios": heights})
    for axis, (name, table) in zip(axes[:, 0], tables):
        axis.axis("off")
        cells = [["all" if e["closed_doors"] == ALL else str(e["closed_doors"]), str(e["cases"]),
                  "%.2f" % e["hidden_percent"]] + ["%.3f" % e["iou_" + m] for m in methods] for e in table]
        drawn = axis.table(cellText=cells, colLabels=["closed doors", "cases", "% hidden"] + methods,
                           loc="upper center", cellLoc="center")
        drawn.auto_set_font_size(False)
        drawn.set_fontsize(8)
        for row, entry in enumerate(table, start=1):
            for column, method in enumerate(methods):
                if method in best_methods(entry, methods):
                    drawn[row, 3 + column].set_text_props(fontweight="bold")
        axis.set_title("%s, %s" % (IOU_LABEL, name), fontsize=9)
    figure.tight_layout()
    paths = save_figure(figure, stem, formats)
    plt.close(figure)
    return paths


def parse_formats(text):
    """The --formats list, in order without repeats; PlotError naming an unknown format."""
    formats = []
    for name in (part.strip().lower().lstrip(".") for part in text.split(",")):
        if name and name not in formats:
            formats.append(name)
    unknown = [name for name in formats if name not in FORMATS]
    if unknown:
        raise PlotError("--formats: unknown format(s) %s (known: %s)" % (", ".join(unknown), ",".join(FORMATS)))
    if not formats:
        raise PlotError("--formats names no format (known: %s)" % ",".join(FORMATS))
    return formats


def main(argv=None):
    parser = ArgumentParser(prog="plot_batch", description="Plots and tables of batch_analysis results.")
    parser.add_argument("folders", nargs="+", metavar="DIR", help="batch_analysis output folder(s)")
    parser.add_argument("--out", help="folder for the plots and tables (default: DIR/plots of the first DIR)")
    parser.add_argument("--formats", default=",".join(FORMATS),
                        help="comma-separated formats of every figure, of %s (default: %%(default)s)" %
                             ", ".join(FORMATS))
    args = parser.parse_args(sys.argv[1:] if argv is None else argv)
    try:
        formats = parse_formats(args.formats)
    except PlotError as error:
        parser.error(str(error))
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
    written = ["table.csv", "table.md", "table.tex"]
    written += plot_by_size_class_panels(os.path.join(out_dir, "iou_vs_closed_doors"), tables, methods, "iou_",
                                         IOU_LABEL, environments, formats)
    written += plot_by_size_class_panels(os.path.join(out_dir, "iou_tot_vs_closed_doors"), tables, methods,
                                         "iou_tot_", IOU_TOT_LABEL, environments, formats)
    written += plot_by_method_panels(os.path.join(out_dir, "iou_by_size_class"), tables, methods, formats)
    written += plot_table(os.path.join(out_dir, "table"), tables, methods, formats)
    print("plot_batch: %d rows, %d environments, %d batches, methods %s -> %s (%s)" % (
        len(rows), environments[grouped[-1][0]], tables[-1][1][-1]["batches"], ",".join(methods), out_dir,
        ", ".join(os.path.basename(path) for path in written)))
    return 0
