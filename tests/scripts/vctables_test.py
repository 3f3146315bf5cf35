"""Tests of scripts/vctables.py: every table of BENCHMARKS.md and docs/ is computed from small
reports made here, and the numbers it prints (medians, ratios, speed-ups, shares) are checked
against the same arithmetic done by hand."""
import contextlib
import csv
import io
import json
import math
import os
import subprocess
import sys
import tempfile
import unittest
import warnings
import zipfile

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "scripts"))
import vctables  # noqa: E402


def run(name, *args):
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        vctables.COMMANDS[name][0](*[str(a) for a in args])
    return out.getvalue()


def dump(path, obj):
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "w") as f:
        json.dump(obj, f)


def row(table, first_cell):
    """The cells of the Markdown table row starting with `first_cell`."""
    for line in table.splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if cells and cells[0] == first_cell:
            return cells
    raise AssertionError(f"no row {first_cell!r} in:\n{table}")


def write_curves(path, rows):
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["method", "cells", "cost", "ratio_to_av_m", "constructed_cost"])
        for r in rows:
            w.writerow(r)


class Tables(unittest.TestCase):
    def setUp(self):
        warnings.simplefilter("ignore", ResourceWarning)  # the tables open report files briefly
        self.tmp = tempfile.TemporaryDirectory()
        self.d = self.tmp.name

    def tearDown(self):
        self.tmp.cleanup()

    def test_merge_start_names_every_piece_of_the_chosen_history(self):
        chain = [{"from_cells": 5000, "to_cells": 78, "greedy_from_cells": 5000, "barrier_cells": 78},
                 {"from_cells": 78, "to_cells": 0, "greedy_from_cells": 39, "barrier_cells": 0}]
        self.assertEqual(vctables.merge_start_text({"chain": chain}), "5,000 / 78, then 39 / -")
        chain[1]["greedy_from_cells"] = 1
        self.assertEqual(vctables.merge_start_text({"chain": chain}), "5,000 / 78, then AV-S")
        chain[1].update({"greedy_from_cells": 312, "barrier_cells": 64, "refined": True})
        self.assertEqual(vctables.merge_start_text({"chain": chain}), "5,000 / 78, then 312 / 64 refined")
        # Reports from before the chain: the single start.
        self.assertEqual(vctables.merge_start_text({"greedy_from_cells": 156, "barrier_cells": 39}), "156 / 39")
        self.assertEqual(vctables.merge_start_text({}, 2000), "2,000 / -")

    def test_two_evaluation_sets_give_each_ratio_the_pooled_one_and_the_spread(self):
        rows = [{"method": m, "cells": str(c), "cost": str(a), "cost_2": str(b)} for m, c, a, b in [
            ("av-m", 16, 102, 98), ("av-s", 16, 100, 100), ("av-m", 20, 90, 99), ("av-s", 20, 100, 100),
            ("av-m", 8, 500, 500), ("av-s", 8, 100, 100)]]
        sets = vctables.evaluation_sets(rows)
        self.assertEqual(len(sets), 2)
        self.assertEqual(sets[1]["av-m"][20], 99.0)
        r = vctables.set_ratios(sets, "av-m", "av-s", [16, 20])  # 8 is not asked for
        self.assertEqual(r["worst"][0], (1.02, 16))
        self.assertEqual(r["worst"][1], (0.99, 20))
        self.assertEqual(r["pooled"], (1.0, 16))  # (102 + 98) / 200; at 20: 189 / 200
        self.assertAlmostEqual(r["spread"][0], 0.09)
        self.assertEqual(r["spread"][1], 20)
        # One set: the cost column alone.
        self.assertEqual(len(vctables.evaluation_sets([{"method": "a", "cells": "1", "cost": "3"}])), 1)

    def test_ab_medians_gives_each_quantity_its_medians_and_ratio(self):
        tsv = f"{self.d}/ab.tsv"
        with open(tsv, "w") as f:
            for side, what, v in [("old", "build s", 2.0), ("new", "build s", 1.0), ("old", "build s", 4.0),
                                  ("new", "build s", 1.5), ("old", "build s", 3.0), ("new", "build s", 9.0),
                                  ("old", "rate", 1000), ("new", "rate", 1500), ("new", "new only", 7)]:
                f.write(f"{side}\t{what}\t{v}\n")
        t = run("ab-medians", tsv, "Title.")
        self.assertIn("Medians of 3 runs a side", t)
        # build s: old 2, 4, 3 -> 3; new 1, 1.5, 9 -> 1.5 (a mean would say 3.83)
        self.assertEqual(row(t, "build s")[1:], ["2, 4, 3", "1, 1.5, 9", "3", "1.5", "0.500"])
        self.assertEqual(row(t, "rate")[3:], ["1,000", "1,500", "1.500"])
        self.assertEqual(row(t, "new only")[1:], ["-", "7", "-", "7", "-"])

    def test_replace_section_keeps_the_rest(self):
        md, table = f"{self.d}/b.md", f"{self.d}/t.md"
        open(md, "w").write("head\n<!-- x:begin -->\nold\n<!-- x:end -->\ntail\n")
        open(table, "w").write("| new |\n")
        run("replace-section", md, "x", "cmd 1", table)
        text = open(md).read()
        self.assertTrue(text.startswith("head\n<!-- x:begin -->\nCommand: `cmd 1`\nMade "), text)
        self.assertTrue(text.endswith("\n\n| new |\n<!-- x:end -->\ntail\n"), text)
        # The date, the commit and the machine it was made on.
        stamp = text.split("\n")[3]
        self.assertRegex(stamp, r"^Made \d{4}-\d{2}-\d{2} at commit \S+.* on \d+ cores, .+\.$")
        with self.assertRaises(SystemExit):
            run("replace-section", md, "missing", "c", table)

    def test_stamp_history_dates_unstamped_sections_from_git(self):
        repo = f"{self.d}/repo"
        os.makedirs(repo)
        git = lambda *a: subprocess.run(["git", "-C", repo, *a], check=True, capture_output=True)
        git("init", "-q")
        git("config", "user.email", "t@t")
        git("config", "user.name", "t")
        md = f"{repo}/b.md"
        open(md, "w").write("<!-- x:begin -->\nCommand: `c`\n\n| 1 |\n<!-- x:end -->\n"
                            "<!-- y:begin -->\nCommand: `d`\nMade 2026-01-01 at commit abc on 2 cores, x.\n<!-- y:end -->\n")
        whole = f"{repo}/w.md"
        open(whole, "w").write("Some maps.\n\n| a |\n| --- |\n| 1 |\n")
        git("add", "b.md", "w.md")
        git("commit", "-q", "-m", "m")
        sha = subprocess.run(["git", "-C", repo, "rev-parse", "--short=7", "HEAD"], capture_output=True,
                             text=True).stdout.strip()
        run("stamp-history", md)
        lines = open(md).read().split("\n")
        self.assertRegex(lines[2], rf"^Recorded \d{{4}}-\d{{2}}-\d{{2}} in commit {sha} \(from git history")
        self.assertEqual(lines[3], "")
        self.assertEqual(lines.count("Made 2026-01-01 at commit abc on 2 cores, x."), 1)  # stamped already: kept
        self.assertEqual(sum(l.startswith("Recorded") for l in lines), 1)
        # A whole generated file gets one line at its end, once.
        run("stamp-history", whole)
        run("stamp-history", whole)
        text = open(whole).read()
        self.assertEqual(text.count("Recorded "), 1)
        self.assertRegex(text, rf"\| 1 \|\nRecorded \S+ in commit {sha} ")

    def test_sampling_medians_and_ratios_to_half_raw(self):
        for name in ["scene-bounds", "street-band"]:
            for r, (seg_rate, raw) in enumerate([(1.0e6, 4e6), (3.0e6, 4e6), (2.0e6, 8e6)], 1):
                dump(f"{self.d}/sample-{name}-{r}.json", {
                    "scene": {"triangles": 1000}, "settings": {"threads": 2},
                    "counts": {"valid_segments": 100 * r, "samples": 200},
                    "timings": {"raw_rays_per_second": raw, "samples_per_second": 1e6, "segments_per_second": seg_rate}})
        t = run("sampling", self.d, 3, 23)
        r = row(t, "scene-bounds")
        self.assertEqual(r[2], "200")           # median segments
        self.assertEqual(r[4], "1.000")         # median valid share 200/200
        self.assertEqual(r[5], "4.00")          # median raw Mrays/s
        self.assertEqual(r[7], "2.00")          # median Msegments/s
        self.assertEqual(r[9], "0.500")         # median of 0.5, 1.5, 0.5

    def test_subdivision_growth_per_doubling(self):
        for n, s in [(500000, 10.0), (1000000, 21.0), (1500000, 33.0), (2000000, 44.1)]:
            for name, secs in [("build", s), ("build-exact", 3 * s)]:
                dump(f"{self.d}/{name}-{n}.json", {
                    "timings": {"load_seconds": 1, "bvh_build_seconds": 1, "sampling_seconds": 1,
                                "subdivision_seconds": secs, "write_seconds": 0.1},
                    "subdivision": {"cells": 50000, "initial_cost": 10, "final_cost": 5, "axis_candidates_evaluated": 7,
                                    "geometry_candidates_evaluated": 0, "segment_parts_evaluated": 9}})
            with open(f"{self.d}/build-{n}.kb", "w") as f:
                f.write("1500000\n")
        os.makedirs(f"{self.d}/compare-candidates")
        with open(f"{self.d}/compare-candidates/curves.csv", "w") as f:
            f.write("method,cells,cost,ratio_to_av_m,constructed_cost\n")
            for cells, cost in [(16, 100.0), (1000, 50.0), (10000, 20.0), (50000, 10.0)]:
                f.write(f"av-s,{cells},{cost},,\n")
                f.write(f"av-s-exact,{cells},{cost * 1.01},,\n")
        dump(f"{self.d}/compare-candidates/summary.json",
             {"methods": [{"method": "av-s", "build_seconds": 30.0}, {"method": "av-s-exact", "build_seconds": 90.0}]})
        t = run("subdivision", self.d, 23, 50000)
        self.assertIn("fast: 1M / 0.5M = 2.10, 2M / 1M = 2.10; exact: 2.10 and 2.10", t)
        r = row(t, "1,500,000")
        self.assertEqual(r[2], "33.0")
        self.assertEqual(r[3], "99.0")
        self.assertEqual(r[4], "3.00")
        self.assertEqual(r[9], "1.50 / -")
        self.assertEqual(row(t, "10,000")[3], "0.9901")
        self.assertIn("subdivision 30.0 s fast, 90.0 s exact", t)

    def dump_city_sizes(self):
        """The city's fast and exact builds at the four sizes, all alike: what the map rows need beside them."""
        for n in (500000, 1000000, 1500000, 2000000):
            for name in ("build", "build-exact"):
                dump(f"{self.d}/{name}-{n}.json", {
                    "timings": {"sampling_seconds": 1, "subdivision_seconds": 10.0},
                    "subdivision": {"final_cost": 5, "axis_candidates_evaluated": 7,
                                    "geometry_candidates_evaluated": 0, "segment_parts_evaluated": 9}})

    def test_subdivision_compare_on_a_map_reports_peak_memory(self):
        self.dump_city_sizes()
        dump(f"{self.d}/compare-map/summary.json", {
            "settings": {"construction_samples": 1000000, "evaluation_samples": 4000000,
                         "methods": ["av-m", "av-s"], "max_cells": 2691},
            "timings": {"load_seconds": 1, "construction_sampling_seconds": 2, "evaluation_sampling_seconds": 3,
                        "evaluation_seconds": 4},
            "methods": [{"method": "av-m", "build_seconds": 10}, {"method": "av-s", "build_seconds": 20}]})
        with open(f"{self.d}/compare-map.kb", "w") as f:
            f.write("1048576\n")
        t = run("subdivision", self.d, 23, 50000)
        self.assertIn("methods av-m, av-s, 2,691 cells): 40 s of loading, sampling, building and evaluating, "
                      "peak memory 1.05 GB (goal: under 2 GB)", t)

    def test_subdivision_map_per_candidate_by_medians_of_one_sitting(self):
        self.dump_city_sizes()
        # Three runs each; the medians are the middle runs: city 10 s for 50M candidates and 200M
        # parts (0.2 µs, 50 ns), map 1.0 s for 1.9M + 0.1M candidates and 20M parts (0.5 µs,
        # 50 ns), map without planes 0.5 s for 2M candidates and 25M parts (0.25 µs, 20 ns).
        for i, (c, m, g) in enumerate([(12.0, 0.9, 0.7), (10.0, 1.2, 0.5), (9.0, 1.0, 0.4)], start=1):
            dump(f"{self.d}/ratio-city-{i}.json", {"timings": {"subdivision_seconds": c}, "subdivision": {
                "axis_candidates_evaluated": 50000000, "geometry_candidates_evaluated": 0,
                "segment_parts_evaluated": 200000000}})
            dump(f"{self.d}/ratio-map-{i}.json", {"timings": {"subdivision_seconds": m}, "subdivision": {
                "axis_candidates_evaluated": 1900000, "geometry_candidates_evaluated": 100000,
                "segment_parts_evaluated": 20000000}})
            dump(f"{self.d}/ratio-map-noga-{i}.json", {"timings": {"subdivision_seconds": g}, "subdivision": {
                "axis_candidates_evaluated": 2000000, "geometry_candidates_evaluated": 0,
                "segment_parts_evaluated": 25000000}})
        t = run("subdivision", self.d, 23, 50000)
        self.assertIn("(3 alternating runs of the city", t)
        self.assertEqual(row(t, "city")[1:], ["10.00", "0.200 (0.180-0.240)", "50.0", "1.00", "1.00"])
        self.assertEqual(row(t, "oa_shouse (GA on)")[1:], ["1.00", "0.500 (0.450-0.600)", "50.0", "2.50", "1.00"])
        self.assertEqual(row(t, "oa_shouse, `--no-ga`")[1:], ["0.50", "0.250 (0.200-0.350)", "20.0", "1.25", "0.40"])
        self.assertIn("time per candidate by these medians: **2.50** (goal: 2); without geometry-aligned planes 1.25.", t)

    def test_candidates_ratios_to_exact_at_200(self):
        for k, fast_cost, exact_cost, fast_s in [(50, 12.0, 11.0, 1.0), (200, 10.5, 10.0, 2.0)]:
            run_dir = f"{self.d}/city-{k}"
            dump(f"{run_dir}/summary.json", {"methods": [{"method": "av-s", "build_seconds": fast_s},
                                                          {"method": "av-s-exact", "build_seconds": 3 * fast_s}]})
            with open(f"{run_dir}/curves.csv", "w") as f:
                f.write("method,cells,cost,ratio_to_av_m,constructed_cost\n")
                for cells, scale in [(16, 4.0), (99, 2.0), (2000, 1.0)]:
                    f.write(f"av-s,{cells},{fast_cost * scale},,\n")
                    f.write(f"av-s-exact,{cells},{exact_cost * scale},,\n")
        t = run("candidates", self.d, 1000000, 2000)
        rows = [line for line in t.splitlines() if line.startswith("| city |")]
        self.assertEqual(len(rows), 2)
        r50 = [c.strip() for c in rows[0].strip("|").split("|")]
        self.assertEqual(r50[1:], ["50", "1.0", "3.0", "3.00", "1.200", "1.200", "1.100", "1.100"])
        self.assertIn("city 1.050-1.050", t)
        dat = run("candidates-dat", self.d).splitlines()
        self.assertEqual(dat[1], "city 50 1.000 3.000 1.2000")

    def test_ab_medians_and_ratio(self):
        tsv = f"{self.d}/ab.tsv"
        with open(tsv, "w") as f:
            for side, v in [("old", 1.0), ("new", 1.1), ("old", 3.0), ("new", 3.3), ("old", 2.0), ("new", 2.2)]:
                f.write(f"{side}\t{v}\t{v}\t{v}\t{v}\t{2 * v}\n")
        t = run("ab", tsv, "abc123", 3, 23)
        r = row(t, "sampling Msegments/s")
        self.assertEqual(r[1:], ["2.00", "2.20", "1.100"])
        self.assertEqual(row(t, "AGVS Msamples/s (office 4, 500 cells)")[1:], ["4.00", "4.40", "1.100"])

    def test_ab_row_reads_both_reports(self):
        dump(f"{self.d}/s.json", {"timings": {"segments_per_second": 2e6, "raw_rays_per_second": 5e6}})
        dump(f"{self.d}/b.json", {"timings": {"subdivision_seconds": 3.5, "merge_seconds": 0.25}})
        self.assertEqual(run("ab-row", "new", f"{self.d}/s.json", f"{self.d}/b.json"), "new\t2.0\t5.0\t3.5\t0.25\n")
        dump(f"{self.d}/p.json", {"samples_per_second": 3e6})
        self.assertEqual(run("ab-row", "old", f"{self.d}/s.json", f"{self.d}/b.json", f"{self.d}/p.json"),
                         "old\t2.0\t5.0\t3.5\t0.25\t3.0\n")

    def agvs_report(self, seconds, mean, entries, curve, est=1.0):
        return {"samples": 1000, "rays": 2000, "seconds": seconds, "mean_pvs_size": mean, "pvs_entries": entries,
                "estimated_pixel_error": est, "pixel_error_bound": None,
                "measured_pixel_error": {"pixels": 2.0}, "curve": curve}

    def test_agvs_speed_up_is_the_time_to_the_same_mean_pvs(self):
        pt = lambda s, m, cov=(0, 0): {"seconds": s, "mean_pvs_size": m, "pixel_error": 1.0, "pixel_error_bound": None,
                                       "covered": list(cov)}
        # AGVS reaches mean 8 at 2 s; SGVS ends at 8 after 10 s: 5 x. 10 cells.
        dump(f"{self.d}/agvs.json", self.agvs_report(10, 9, 90, [pt(1, 5, (30, 30)), pt(2, 8, (76, 70)), pt(10, 9, (80, 80))]))
        dump(f"{self.d}/sgvs.json", self.agvs_report(10, 8, 80, [pt(4, 7), pt(10, 8)]))
        dump(f"{self.d}/ref.json", self.agvs_report(10, 6, 60, [pt(5, 6), pt(10, 6)]))
        t = run("agvs", self.d, "office", 4, 10, 10)
        self.assertEqual(row(t, "SGVS")[6:8], ["2.00 s", "5.0 x"])
        self.assertEqual(row(t, "REF")[6:8], ["2.00 s", "5.0 x"])  # AGVS passes 6 at 2 s too
        # Entries: SGVS finds 95% of its 80 entries (76) at 10 s; AGVS covers 76 at 2 s.
        sg = [r for r in t.splitlines() if r.startswith("| SGVS | 80")][0]
        self.assertIn("| 10.00 s | 2.00 s | 5.0 x |", sg)
        self.assertTrue(os.path.exists(f"{self.d}/agvs.dat"))

    def test_estimator_counts_stops_within_a_factor_of_two(self):
        for m in ("sgvs", "agvs"):
            for n, est, meas in [(1000, 4.0, 2.5), (2000, 1.0, 3.0), (4000, None, 1.0)]:
                dump(f"{self.d}/{m}-{n}.json", {"samples": n, "mean_pvs_size": 5, "estimated_pixel_error": est,
                                               "pixel_error_bound": 0.5 if est is None else None,
                                               "measured_pixel_error": {"pixels": meas}, "estimator_window_rays": 9})
        t = run("estimator", self.d, "office", 4, 500, 4000, 100, 32)
        self.assertIn("AGVS: the estimate is within a factor of 2 of the measurement at 1 of 2 stops", t)
        self.assertIn("| < 0.50 |", t)

    def test_filter_growth(self):
        for n in (100000, 1000000, 10000000):
            for f in ("object", "both"):
                dump(f"{self.d}/{f}-{n}.json", {"samples": n, "measured_pixel_error": {"pixels": 1.0},
                                               "filter": {"mean_pvs_size_unfiltered": 10.0, "mean_pvs_size_filtered": 12.5,
                                                          "measured_pixel_error_unfiltered": {"pixels": 3.0}}})
        t = run("filter", self.d, "office", 4, 500)
        self.assertIn("| 1,000,000 | object space | 10.00 | 12.50 | 1.25 x | 3.00 | 1.00 |", t)

    def test_merging_table(self):
        for name, n in [("city", 8), ("office", 4)]:
            dump(f"{self.d}/merge-{name}.json", {
                "final_cost": 100.0,
                "merge": {"cells_from": n, "pair_costs_evaluated": 5, "stale_entries_skipped": 2,
                          "cost_at_power_of_two_cells": [{"cells": 1, "cost": 400.0}, {"cells": 2, "cost": 300.0},
                                                         {"cells": 4, "cost": 200.0}, {"cells": 8, "cost": 100.0}]},
                "timings": {"subdivision_seconds": 2.0, "merge_seconds": 0.5, "leaf_pvs_seconds": 1.5,
                            "neighbour_graph_seconds": 0.25}})
        for name, counts in [("city", [8, 5000, 500, 50]), ("office", [2000, 200, 20])]:
            for c in counts:
                dump(f"{self.d}/compress-{name}-{c}.json", {
                    "cells": c, "objects": 10, "entries_before": 100, "entries_after": 40, "entry_ratio": 0.4,
                    "list_bytes_before": 150, "list_bytes_after": 60, "file_bytes": 500,
                    "flat": {"bit_row_bytes": 20, "run_length_bytes": 15}})
        with open(f"{self.d}/merge-stage.txt", "w") as f:
            f.write("run 0: cells 8, neighbour graph 0.300 s, merge 1.500 s\n"
                    "fastest: neighbour graph 0.250 s, merge 1.250 s\n")
        t = run("merging", self.d, 23, 8)
        self.assertIn("fastest of 3 runs): neighbour graph 0.250 s, merge 1.250 s.", t)
        # 8 / 10 is nearest 1
        self.assertIn("| city | construction samples | 8 | 2.0 | 1.50 | 0.25 | 0.50 | 2.25 | 5 | 8 / - | 100 | 400 (1) | 400 (1) |", t)
        self.assertIn("| office | 200 | 10 | 100 | 40 | 0.400 |", t)

    def test_compare_histogram_shares_sum_to_one(self):
        os.makedirs(f"{self.d}/c")
        with open(f"{self.d}/c/histogram.csv", "w") as f:
            f.write("method,cell,cost,volume\nav-m,0,10,1\nav-m,1,240,3\nkd,0,120,2\n")
        run("compare-histogram", f"{self.d}/c")
        lines = open(f"{self.d}/c/histogram.dat").read().split("\n")
        self.assertEqual(lines[0], "cost av-m kd")
        cols = [[float(x) for x in l.split()[1:]] for l in lines[1:] if l]
        self.assertAlmostEqual(sum(c[0] for c in cols), 1.0)
        self.assertAlmostEqual(sum(c[1] for c in cols), 1.0)
        self.assertAlmostEqual(cols[-1][0], 0.75)  # the top bin holds av-m's cell of cost 240

    def test_compare_methods_get_street_band_and_unpack(self):
        write_curves(f"{self.d}/curves.csv", [["av-m", 1, 5, 1, 5], ["kd", 1, 6, 1.2, 6], ["av-m", 2, 4, 1, 4]])
        self.assertEqual(run("compare-methods", f"{self.d}/curves.csv"), "av-m kd\n")
        dump(f"{self.d}/info.json", {"bounds": {"min": [1, 2, 3], "max": [4, 5, 6]}, "quake3": {"clusters": 7}})
        self.assertEqual(run("get", f"{self.d}/info.json", "quake3", "clusters"), "7\n")
        self.assertEqual(run("street-band", f"{self.d}/info.json"), "1,2,0.0,4,5,30.0\n")
        with zipfile.ZipFile(f"{self.d}/a.pk3", "w") as z:
            z.writestr("maps/m1.bsp", b"IBSP1")
            z.writestr("textures/x.jpg", b"no")
        os.makedirs(f"{self.d}/out")
        run("unpack-maps", f"{self.d}/a.pk3", f"{self.d}/out")
        self.assertEqual(os.listdir(f"{self.d}/out"), ["m1.bsp"])

    def compare_run(self, name, methods, curves, q3=None):
        rows = []
        for m, pts in curves.items():
            for c, cost in pts.items():
                rows.append([m, c, cost, "", cost * 0.9])
        write_curves(f"{self.d}/{name}/curves.csv", rows)
        s = {"scene": {"triangles": 100, "objects": 10},
             "effects": {"empty_space_detection": {"reason": "enabled"}},
             "timings": {"construction_sampling_seconds": 1, "evaluation_sampling_seconds": 2, "evaluation_seconds": 3},
             "methods": [{"method": m, "cells": max(curves[m]), "build_seconds": 1.5, "axis_candidates_evaluated": 10,
                          "geometry_candidates_evaluated": 0, "evaluated_cost_at_most_cells": curves[m][max(curves[m])]}
                         for m in methods]}
        if q3:
            s["q3map2"] = q3
        dump(f"{self.d}/{name}/summary.json", s)

    def test_results_ratios_to_av_m(self):
        methods = ["av-m", "av-s", "kd-casm", "kd-lasm", "kd-vt", "kd-vt-star", "bsp"]
        for name in ["office", "rotated-office", "city"]:
            curves = {m: {10: 100.0 * (1 + k / 10), 100: 80.0 * (1 + k / 10), 1000: 50.0 * (1 + k / 10)}
                      for k, m in enumerate(methods)}
            self.compare_run(f"compare-{name}", methods, curves)
        t = run("results", self.d, 1000, 1000, 23)
        self.assertEqual(row(t, "KD-CASM")[-1], "1.200")  # kd-casm / av-m at 1,000 cells
        self.assertIn("17% below at 1,000 cells", t)        # 1 - 50 / 60
        # The worst ratios from 16 cells up: AV-M / AV-S is 1 / 1.1 everywhere, AV-M / KD-CASM 1 / 1.2.
        self.assertIn("| office (size 4, two storeys) | 0.909 at 100 | - | 0.833 at 100 |", t)

    def test_accuracy_plot_data(self):
        for n in [50000, 200000, 1000000, 2000000]:
            write_curves(f"{self.d}/samples-office-{n}/curves.csv", [["av-s", 10, n / 1000, "", 1], ["av-s", 20, 1, "", 1]])
        dat = run("accuracy-samples-dat", self.d, "office").splitlines()
        self.assertEqual(dat[0], "cells 50k 200k 1000k 2000k")
        self.assertEqual(dat[1], "10 50.0 200.0 1000.0 2000.0")
        write_curves(f"{self.d}/ga-off/curves.csv", [["av-s", 10, 6.0, "", 1]])
        write_curves(f"{self.d}/ga-150/curves.csv", [["av-s", 10, 4.0, "", 1]])
        self.assertEqual(run("ga-ratio-dat", self.d), "10 1.5\n")

    def test_maps_table(self):
        q3 = {"clusters": 10, "q3map2_cost": 200.0, "av_m_cost_at_clusters": 150.0, "av_m_cost_ratio": 0.75,
              "av_m_cells_to_match": 5, "pvs_size_ratio": 0.8, "excluded_but_seen": 3,
              "excluded_by_cause": {"crack": 2, "void": 1},
              "storage_bytes": {"q3map2_rows": 1000, "q3map2_leaf_surface_lists": 50, "ours_compressed": 250,
                                "ours_rle_rows": 400}, "build_seconds": 2.0}
        out = f"{self.d}/maps"
        for name, avs in [("m1", 150.0), ("m2", 140.0)]:
            self.compare_run(f"maps/{name}", ["av-m", "av-s"], {"av-m": {2: 300.0, 10: 150.0},
                                                                 "av-s": {2: 310.0, 10: avs}}, q3)
            dump(f"{out}/{name}.info.json", {"quake3": {"surfaces": {"non_occluding": 1}}})
            open(f"{out}/{name}/wall_seconds", "w").write("4.0")
        dump(f"{out}/m3.info.json", {"quake3": {"surfaces": {"non_occluding": 0}}})
        open(f"{out}/m3.skipped", "w").write("no visibility data")
        cwd = os.getcwd()
        os.makedirs(f"{self.d}/docs/results")
        os.chdir(self.d)
        try:
            run("maps", out, 1000, 4000)
            md = open("docs/results/q3-maps.md").read()
        finally:
            os.chdir(cwd)
        self.assertIn("(2 maps; 1 without vis data skipped)", md)
        self.assertIn("lower than q3map2's on 2 of 2 maps**: AV-M / q3map2 median 0.750", md)
        self.assertIn("500 B (0.25 x the rows", md)  # 500 / 2000 B over both maps
        # AV-M / AV-S at the 10 clusters: 1.000 (m1) and 150 / 140 (m2); at a quarter (2 cells) 300 / 310.
        self.assertIn("AV-M / AV-S at q3map2's cluster count: at most 1 on 1 of 2 maps, at most 1.02 on 1; "
                      "median 1.036, worst 1.071 (m2)", md)
        self.assertIn("AV-M / AV-S at a quarter of it: at most 1 on 2 of 2 maps", md)

    def test_shipped_table(self):
        out = f"{self.d}/shipped"

        def measured(cells, cost, err, median, pvs_bytes, causes=None):
            return {"cells": cells, "cameras": {"count": 100}, "frame": {"cost": cost, "triangles": cost / 2},
                    "pixel_error": {"pixels": err, "median_pixels": median, "by_cause": causes or {},
                                    "cameras_with_wrong_pixels": 3},
                    "storage_bytes": pvs_bytes + 10, "pvs_bytes": pvs_bytes, "leaf_surface_bytes": 100}
        bake = {"estimated_pixel_error": None, "pixel_error_bound": 1.5, "agvs": {"samples": 1000}}
        # m1: ours at the clusters fits the rows; m2: it does not, the bake that fits the rows costs
        # 0.6, the one within rows + leaf lists (1,110 bytes) 0.48; m3: it does not and nothing fits,
        # but rows + leaf lists hold it; m5: it fits but costs 0.6, and the most cells that fit (20)
        # cost 0.45; m6: it fits and costs 0.7, nothing else made.
        for name, ours_cost, ours_bytes, fit, fit_leaf in [
                ("m1", 40.0, 900, None, None), ("m2", 30.0, 2000, (5, 60.0, 950), (8, 48.0, 1080)),
                ("m3", 45.0, 1050, None, None), ("m5", 60.0, 700, (20, 45.0, 990), None),
                ("m6", 70.0, 900, None, None)]:
            dump(f"{out}/{name}/q3map2.json", measured(10, 100.0, 0.0, 0.0, 1000, {"far": 4}))
            dump(f"{out}/{name}/ours.json", measured(10, ours_cost, 2.0, 0.0, ours_bytes))
            dump(f"{out}/{name}/bake.json", bake)
            open(f"{out}/{name}/bake_wall_seconds", "w").write("12.5")
            if fit:
                dump(f"{out}/{name}/fit.json", measured(fit[0], fit[1], 3.0, 0.0, fit[2]))
            if fit_leaf:
                dump(f"{out}/{name}/fit-leaf.json", measured(fit_leaf[0], fit_leaf[1], 3.0, 0.0, fit_leaf[2]))
        os.makedirs(f"{out}/m4")
        open(f"{out}/m4.skipped", "w").write("no visibility data")
        # What maps-shipped.sh asks before the third bake.
        self.assertEqual(run("shipped-budget", f"{out}/m2").strip(), "1110")
        self.assertEqual(run("shipped-met", f"{out}/m6", 1100).strip(), "no")
        self.assertEqual(run("shipped-met", f"{out}/m1", 1100).strip(), "yes")
        self.assertEqual(run("shipped-ratio", f"{out}/m2", "fit-leaf").strip(), "0.480")
        cwd = os.getcwd()
        os.makedirs(f"{self.d}/docs/results")
        os.chdir(self.d)
        try:
            run("shipped", out, 1, 45)
            md = open("docs/results/q3-shipped.md").read()
            misses = run("shipped-misses", "docs/results/q3-shipped.csv").split()
            # The third bake for m6 (as maps-shipped-leaf.sh makes it), within its 1,110 bytes.
            leaf = f"{self.d}/leaf"
            dump(f"{leaf}/m6/q3map2.json", measured(10, 100.0, 0.0, 0.0, 1000))
            dump(f"{leaf}/m6/fit-leaf.json", measured(12, 49.0, 0.5, 0.0, 1090))
            dump(f"{leaf}/m6/fit-leaf-bake.json", {"timings": {"total_seconds": 30.0}})
            run("shipped-leaf", leaf, "docs/results/q3-shipped.csv", 1, 45)
            leaf_md = open("docs/results/q3-shipped-leaf.md").read()
            still = run("shipped-misses", "docs/results/q3-shipped.csv", "docs/results/q3-shipped-leaf.csv").split()
            # --play-space on a map that met the goal without it.
            pc = f"{self.d}/pc"
            dump(f"{pc}/m1/q3map2.json", measured(10, 100.0, 0.0, 0.0, 1000))
            dump(f"{pc}/m1/fit-play.json", measured(11, 35.0, 0.2, 0.0, 1000))
            dump(f"{pc}/m1/fit-play-bake.json", {"timings": {"total_seconds": 20.0}})
            run("shipped-leaf", pc, "docs/results/q3-shipped.csv", 1, 45, "--play-space", "m1")
            check_md = open("docs/results/q3-shipped-play-check.md").read()
            # --play-space on every map of the table (maps-shipped-leaf.sh --play-space all): m6's cut
            # misses half the cost, m3's bake made no cut.
            pa = f"{self.d}/pa"
            for name, got in [("m1", (11, 35.0, 0.2, 1000)), ("m2", (9, 45.0, 0.4, 1100)), ("m3", None),
                              ("m5", (21, 40.0, 0.3, 1000)), ("m6", (13, 55.0, 2.5, 1050))]:
                dump(f"{pa}/{name}/q3map2.json", measured(10, 100.0, 0.0, 0.0, 1000))
                if got:
                    dump(f"{pa}/{name}/fit-play.json", measured(got[0], got[1], got[2], 0.0, got[3]))
                    dump(f"{pa}/{name}/fit-play-bake.json", {"timings": {"total_seconds": 30.0}})
            run("shipped-leaf", pa, "docs/results/q3-shipped.csv", 1, 45, "--play-space", "all")
            all_md = open("docs/results/q3-shipped-play-all.md").read()
        finally:
            os.chdir(cwd)
        self.assertIn("5 maps (1 without vis data skipped)", md)
        self.assertEqual(row(md, "m1")[4], "0.400")
        self.assertEqual(row(md, "m2")[12], "5, 0.600, 3.00")
        self.assertEqual(row(md, "m2")[13], "8, 0.480, 3.00")
        self.assertEqual(row(md, "m3")[12], "none")
        self.assertEqual(row(md, "m5")[12], "20, 0.450, 3.00")
        self.assertEqual([row(md, m)[14] for m in ("m1", "m2", "m3", "m5", "m6")],
                         ["yes / yes", "no / yes", "no / yes", "yes / yes", "no / no"])
        self.assertIn("median over maps; range 0.300 to 0.700", md)
        self.assertIn("All three (cost at most half, median camera at most 1 wrong pixel, within the rows' bytes, by "
                      "either bake): 2 of 5 maps", md)
        self.assertIn("20 far", md)
        self.assertEqual(misses, ["m6"])
        self.assertEqual(row(leaf_md, "m6")[4:7], ["12", "0.490", "0.50 / 0"])
        self.assertIn("1 of these 1 maps meet all three", leaf_md)
        self.assertIn("with the 4 that met it before, 5 of 5 maps", leaf_md)
        self.assertEqual(still, [])
        self.assertEqual(row(check_md, "m1")[4:6], ["11", "0.350"])
        self.assertIn("1 of these 1 maps meet all three within q3map2's rows and leaf surface lists with --play-space** (1 met",
                      check_md)
        self.assertIn("median 0.875", check_md)
        self.assertEqual([row(all_md, m)[9] for m in ("m1", "m2", "m3", "m5", "m6")], ["yes", "yes", "no", "yes", "no"])
        self.assertIn("**3 of 5 maps meet all three within q3map2's rows and leaf surface lists with this one bake "
                      "setting** (cost at most half of q3map2's per frame, median camera at most 1 wrong pixel, lists "
                      "within the bytes; goal: 5)", all_md)
        self.assertIn("Ours / q3map2: median 0.425", all_md)
        self.assertIn("largest 2.50 (m6)", all_md)
        self.assertIn("Missing the goal: m3 (no cut fits), m6 (0.550, median 0 px).", all_md)

    def test_agvs_measured_time_to_error(self):
        out = f"{self.d}/am"

        def pvs(curve, end):
            return {"cells": 50, "samples": end[2], "seconds": end[0], "measured_pixel_error": {"pixels": end[1]},
                    "measured_curve": [{"seconds": t, "measured_pixels": e, "samples": n} for t, e, n in curve]}
        # AGVS: 1000 px at 1 s, 10 px at 10 s; SGVS: 1000 px at 4 s, ends at 100 px after 100 s; REF never below 1000.
        dump(f"{out}/s/agvs.json", pvs([(1, 1000, 10), (10, 10, 100)], (20, 5, 200)))
        dump(f"{out}/s/sgvs.json", pvs([(4, 1000, 10), (100, 100, 100)], (100, 100, 100)))
        dump(f"{out}/s/ref.json", pvs([(1, 5000, 10)], (100, 2000, 100)))
        t = run("agvs-measured", out, 100, "s")
        agvs = row(t, "s")
        self.assertEqual(agvs[2], "AGVS")
        self.assertEqual(agvs[6:8], ["1.00 s", "3.16 s"])  # 100 px: halfway on the log-log line from 1 s to 10 s
        sgvs = [r for r in t.splitlines() if "| SGVS |" in r][0]
        self.assertIn("4.00 s (4.0 x)", sgvs)
        self.assertIn("100.00 s (31.6 x)", sgvs)
        ref = [r for r in t.splitlines() if "| REF |" in r][0]
        self.assertIn("not reached (> 100 x)", ref)  # 1,000 px: AGVS at 1 s, REF not within 100 s
        self.assertTrue(os.path.exists(f"{out}/s/agvs.dat"))

    def test_runtime_table(self):
        bench = {"context": {"num_cpus": 2, "mhz_per_cpu": 2450, "library_version": "v1.7.1"},
                 "benchmarks": [{"name": "BM_Locate", "run_type": "iteration", "cpu_time": 125.0, "time_unit": "ns",
                                 "items_per_second": 8e6, "cells": 50000, "objects": 8100, "memory_MB": 80.0},
                                {"name": "BM_LocateAndList", "run_type": "iteration", "cpu_time": 0.2, "time_unit": "us",
                                 "items_per_second": 5e6, "cells": 50000, "objects": 8100, "memory_MB": 80.0}]}
        dump(f"{self.d}/r.json", bench)
        t = run("runtime", f"{self.d}/r.json", 50000, 8100)
        # With repetitions, the medians are reported.
        med = dict(bench["benchmarks"][0], name="BM_Locate_median", run_name="BM_Locate", run_type="aggregate",
                   aggregate_name="median", repetitions=7, cpu_time=100.0, items_per_second=1e7)
        mean = dict(med, name="BM_Locate_mean", aggregate_name="mean", cpu_time=300.0, items_per_second=3e6)
        dump(f"{self.d}/m.json", dict(bench, benchmarks=[mean, med]))
        tm = run("runtime", f"{self.d}/m.json", 50000, 8100)
        self.assertIn("| point location only | 100 | 10.00 |", tm)
        self.assertIn("medians of 7 repetitions", tm)
        self.assertIn("| point location only | 125 | 8.00 |", t)
        self.assertIn("| 200 | 5.00 |", t)
        self.assertIn("50,000 view cells over 8,100 objects (`compress --count 50,000`", t)
        self.assertIn("One core (taskset) of 2 at 2.5 GHz", t)
        self.assertNotIn("ms to open", t)
        # Opening the file in both formats, a row each with its bytes; a skipped run is left out.
        opens = [{"name": "BM_Open", "run_type": "iteration", "real_time": 310.4, "time_unit": "ms",
                  "items_per_second": 3.2},
                 {"name": "BM_OpenFormat1", "run_type": "iteration", "real_time": 0.25, "time_unit": "s",
                  "items_per_second": 4.0},
                 {"name": "BM_OpenCompact", "run_type": "iteration", "real_time": 200.0, "time_unit": "ms",
                  "items_per_second": 5.0}]
        dump(f"{self.d}/o.json", dict(bench, benchmarks=bench["benchmarks"] + opens))
        to = run("runtime", f"{self.d}/o.json", 50000, 8100, 1000000, 2000000)
        self.assertIn("| 2 | 1,000,000 | 310 |", to)
        self.assertIn("| 1 | 2,000,000 | 250 |", to)
        self.assertIn("| 2, compact handle | 1,000,000 | 200 |", to)
        skipped = dict(opens[1], error_occurred=True)
        dump(f"{self.d}/s.json", dict(bench, benchmarks=bench["benchmarks"] + [opens[0], skipped]))
        ts = run("runtime", f"{self.d}/s.json", 50000, 8100, 1000000, 2000000)
        self.assertIn("| 2 | 1,000,000 | 310 |", ts)
        self.assertNotIn("| 1 |", ts)


class Cli(unittest.TestCase):
    def test_unknown_command_and_help(self):
        err = io.StringIO()
        with contextlib.redirect_stderr(err):
            self.assertEqual(vctables.main(["vctables", "nope"]), 2)
        self.assertIn("no command 'nope'", err.getvalue())
        out = io.StringIO()
        with contextlib.redirect_stdout(out):
            self.assertEqual(vctables.main(["vctables", "--help"]), 0)
        for name in ["sampling", "results", "maps", "runtime", "replace-section"]:
            self.assertIn(name, out.getvalue())



class MpiModelTest(unittest.TestCase):
    def test_model_from_measured_runs(self):
        with tempfile.TemporaryDirectory() as d:
            path = os.path.join(d, "runs.jsonl")
            lines = []
            # Seconds of 1,000 samples per phase for (ranks, threads), with 64 lanes:
            # drawing repeated on every rank, a node's two threads dividing 80% of it;
            # the lanes and casting divided by ranks and threads alike;
            # applying half repeated on every rank and half divided, threads dividing half.
            phases = {(1, 1): (0.1, 0.04, 1.0, 0.2), (1, 2): (0.06, 0.02, 0.5, 0.15), (2, 1): (0.1, 0.02, 0.5, 0.15)}
            for cells, pierced in ((500, 2000), (5000, 4000)):
                runs = [(ranks, threads, 64, phases[(ranks, threads)]) for ranks, threads in phases]
                runs.append((1, 1, 1, (0.1, 0.03, 1.0, 0.2)))  # one lane: its mutations take 0.03 s
                if cells == 500:  # a repeat of the first configuration, slower: the medians take 0.1 s
                    runs += [(1, 1, 64, (0.1, 0.04, 1.0, 0.2)), (1, 1, 64, (0.9, 0.9, 9.0, 0.9))]
                for ranks, threads, lanes, (draw, mutation, cast, apply) in runs:
                    lines.append({"kind": "pvs", "cells": cells, "lanes": lanes, "ranks": ranks, "threads": threads,
                                  "samples": 1000, "seconds": 2.0,
                                  "phases": {"draw_seconds": draw, "mutation_seconds": mutation,
                                             "cast_seconds": cast, "apply_seconds": apply,
                                             "segments": 1000, "pierced_cells": pierced},
                                  "cluster": {"exchanges": 4 * (ranks - 1), "bytes_sent": 50000 * (ranks - 1),
                                              "bytes_received": 50000 * (ranks - 1), "exchange_seconds": 0.1}})
            with open(path, "w") as f:
                f.write("\n".join(json.dumps(x) for x in lines) + "\n")
            out = run("mpi-model", path)
        self.assertIn("Medians of 3 runs", out)
        # Per sample in µs: repeated + divided among ranks (serial share among a node's cores).
        cells = row(out, "500")
        self.assertEqual(cells[1:8], ["100.00 + 0.00 (20%)", "0.00 + 40.00 (0%)", "0.00 + 1000.00 (0%)",
                                      "100.00 + 100.00 (50%)", "30.00", "200", "2.0"])
        # Pierced cells double per tenfold cells: at 50,000 cells 8 per segment, applying doubled.
        self.assertIn("cells^0.30", out)
        self.assertEqual(row(out, "50,000")[4], "200.00 + 200.00 (50%)")
        rows = [l for l in out.splitlines() if l.startswith("| 500 | 1.0 (100%)")]
        self.assertEqual(len(rows), 3)

        # Routed: all ranks' bytes are twice what rank 0 sent and received at two ranks (200 a
        # sample), of which a rank receives (n - 1) / n^2.
        def exchange(n):
            return (n - 1) / n ** 2 * 200 / 1e10 + (5 * math.ceil(math.log2(n)) * 5e-6 / 20000 if n > 1 else 0)

        def node(r, dv, share, n):
            return (r + dv / n) * (share + (1 - share) / 32)

        def built(n, one_lane):
            mutation = 3e-5 if one_lane else node(0, 4e-5, 0, n)
            return (node(1e-4, 0, 0.2, n) + mutation + node(0, 1e-3, 0, n) + node(1e-4, 1e-4, 0.5, n)
                    + exchange(n))

        def bound(n):
            return (1e-4 + 4e-5 + 1e-3 + 2e-4) / (32 * n) + exchange(n)

        for k, t in enumerate((lambda n: built(n, False), lambda n: built(n, True), bound)):
            self.assertEqual(rows[k].split("|")[3].strip(), f"{t(1) / t(2):.1f} ({100 * t(1) / t(2) / 2:.0f}%)")
            self.assertEqual(rows[k].split("|")[8].strip(), f"{t(1) / t(64):.1f} ({100 * t(1) / t(64) / 64:.0f}%)")
        # One node of 32 cores over one core, and the model's bytes received at four ranks
        # (no four-rank run here: not measured).
        one_node = [l for l in out.splitlines() if l.startswith("| 500 |") and l.endswith("% |") and "x |" in l]
        self.assertEqual(len(one_node), 1)
        fields = [f.strip() for f in one_node[0].split("|")[1:-1]]
        self.assertEqual(fields[1], f"{(1e-4 + 4e-5 + 1e-3 + 2e-4) / built(1, False):.1f}x")
        self.assertEqual(fields[2], "- / 38")



class BenchDriver(unittest.TestCase):
    """scripts/bench.sh: every command file is listed, help shows a command's usage, and a wrong
    command or a missing earlier commit is an error before anything is built."""
    root = os.path.join(os.path.dirname(__file__), "..", "..")

    def bench(self, *args):
        return subprocess.run(["bash", os.path.join(self.root, "scripts", "bench.sh"), *args], capture_output=True,
                              text=True, timeout=60)

    def test_lists_every_command_and_refuses_unknown_ones(self):
        listed = self.bench("help")
        self.assertEqual(listed.returncode, 0)
        names = sorted(f[:-3] for f in os.listdir(os.path.join(self.root, "scripts", "bench")) if f.endswith(".sh"))
        self.assertGreater(len(names), 15)
        for name in names:
            self.assertRegex(listed.stdout, rf"\n  {name} +\S")
        self.assertIn("Usage: scripts/bench.sh ab-io OLD_COMMIT", self.bench("help", "ab-io").stdout)
        self.assertEqual(self.bench("no-such-benchmark").returncode, 2)
        missing = self.bench("ab-io")
        self.assertNotEqual(missing.returncode, 0)
        self.assertIn("OLD_COMMIT", missing.stderr)
        self.assertEqual(self.bench("ab-io", "not-a-commit-anywhere").returncode, 2)

if __name__ == "__main__":
    unittest.main()
