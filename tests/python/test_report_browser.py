"""The HTML report renders its plots in headless Chromium without script errors."""
import os
import csv as csv_lib
import html as html_lib
import io
import json
import re
import shutil
import subprocess

import pytest

import trueaxis

TRUEAXIS = os.environ.get("TRUEAXIS", "trueaxis")


def chromium():
    for name in ("chromium", "chromium-browser", "google-chrome"):
        path = shutil.which(name)
        if path:
            return path
    raise RuntimeError("Chromium is needed for the report test (Debian package 'chromium')")


def dump_dom(html, tmp_path):
    out = subprocess.run(
        [chromium(), "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
         "--disable-background-networking", "--disable-component-update", "--disable-sync",
         f"--user-data-dir={tmp_path / 'profile'}", "--virtual-time-budget=5000", "--dump-dom",
         f"file://{html}"],
        capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    return out.stdout


def plot_csvs(html, tmp_path):
    """The CSV each plot's link makes when clicked, as lists of rows (the page builds it)."""
    page = tmp_path / "csv-probe.html"
    probe = """<script>
document.querySelectorAll('a[data-plot]').forEach(function(a, i){
  a.addEventListener('click', function(e){ e.preventDefault(); });
  a.click();
  fetch(a.href).then(function(r){ return r.text(); }).then(function(t){
    var pre = document.createElement('pre'); pre.id = 'csv-' + i; pre.textContent = t;
    document.body.appendChild(pre);
  });
});
</script></body>"""
    page.write_text(open(html, encoding="utf-8").read().replace("</body>", probe), encoding="utf-8")
    dom = dump_dom(page, tmp_path)
    out = {}
    for i, text in re.findall(r'<pre id="csv-(\d+)">(.*?)</pre>', dom, re.S):
        out[int(i)] = list(csv_lib.reader(io.StringIO(html_lib.unescape(text))))
    return out


def test_demo_report_renders_every_plot(tmp_path):
    report = tmp_path / "demo" / "index.html"
    subprocess.run([TRUEAXIS, "demo", "-o", str(report), "-q"], check=True)  # as the README runs it
    # A page to hand over: at most 1.5 MB, opening with its contents, each scenario in one line
    # with its headline figure and a link to it.
    assert report.stat().st_size <= 1.5e6, report.stat().st_size
    page = report.read_text(encoding="utf-8")
    toc = re.search(r'<nav class="toc"><h2>Contents</h2><ol>(.*?)</ol></nav>', page, re.S)
    assert toc, "no contents"
    entries = re.findall(r'<li><a href="#(s\d+)">([^<]+)</a>: ([^<]+)', toc.group(1))
    titles = re.findall(r'<h2 id="(s\d+)">([^<]+)</h2>', page)
    assert [(i, t) for i, t, _ in entries] == titles and len(titles) >= 10, (entries, titles)
    assert all(re.search(r"\d", headline) for _, _, headline in entries), entries
    # The showcase says in words how it ends: the CMM that fails E0 passes once corrected, and
    # the error space carries no warning against its own grid.
    assert re.search(r"before correction FAIL; after: grid PASS, parametric PASS", page)
    assert "finer than this campaign supports" not in page
    dom = dump_dom(report, tmp_path)
    total = re.search(r'data-plots-total="(\d+)"', dom)
    rendered = re.search(r'data-plots-rendered="(\d+)"', dom)
    assert total and rendered, "report script did not run"
    # 8 straightness plots, the compensation curves and the five guideway errors.
    assert int(total.group(1)) >= 14
    assert rendered.group(1) == total.group(1)
    assert 'data-script-errors="' not in dom, "script errors in the report"
    assert dom.count("<canvas") >= int(total.group(1))
    # The SVG figures: Moody's plate and its closure (classic and least squares), the space's
    # level surfaces, uncertainty and three distorted planes. Each must be in the rendered DOM
    # with a non-empty size.
    figures = re.search(r'data-figures-total="(\d+)"', dom)
    assert figures and int(figures.group(1)) >= 4 + 3 + 3
    assert dom.count('<svg class="ta-fig"') == int(figures.group(1))
    assert dom.count("the surface in 3-D") >= 2  # Moody's plate, classic and least squares
    # The scanning scenario: two parts of a batch, each section drawn in its plane.
    assert dom.count("in its plane: deviations from the design") == 4 * 2  # caption, label
    assert "Error-tolerant scanning, part 2 of a batch" in dom
    assert "Positioning accuracy of the X axis (ISO 230-2)" in dom
    for name in ("machine.json", "space.json", "x.comp", "surface-moody-lsq.json", "moody/Config.txt",
                 "layout.json", "spots.csv", "ipp_simple.stp", "design.json", "part1.json",
                 "scan1.json", "scan2.json", "design-corrected.json", "runs.csv", "runs.rtl",
                 "x-positioning.comp", "X.COM", "x-pitch.txt", "x_lec.mpf"):
        assert (report.parent / name).stat().st_size > 0, name
    # The positioning runs as Renishaw's .rtl file give the CSV's evaluation; the axis
    # compensated with the HEIDENHAIN table is measured again in the report.
    rtl = trueaxis.positioning(str(report.parent / "runs.rtl"))
    csv = trueaxis.positioning(str(report.parent / "runs.csv"))
    assert rtl["A"] == pytest.approx(csv["A"], abs=1e-3) and rtl["B_mean"] < -2
    after = re.search(r"Compared with the axis before compensation [^:]*: accuracy A "
                      r"([0-9.]+) µm → ([0-9.]+) µm", dom)
    assert after and float(after.group(2)) < float(after.group(1)) / 2
    assert "<h3>before and after compensation — A " in dom


def evaluate_in(html, tmp_path, expression):
    """The JSON value of a JavaScript expression evaluated in the report's page."""
    page = tmp_path / "probe.html"
    probe = ("<script>var pre=document.createElement('pre');pre.id='probe';"
             f"pre.textContent=JSON.stringify({expression});document.body.appendChild(pre);</script></body>")
    page.write_text(open(html, encoding="utf-8").read().replace("</body>", probe), encoding="utf-8")
    found = re.search(r'<pre id="probe">(.*?)</pre>', dump_dom(page, tmp_path), re.S)
    assert found, "the probe did not run"
    return json.loads(html_lib.unescape(found.group(1)))


def test_report_command_renders(tmp_path):
    p, t, r, h = (tmp_path / n for n in ("p.csv", "t.csv", "r.json", "r.html"))
    subprocess.run([TRUEAXIS, "simulate", "straightness", "-o", str(p), "--truth", str(t), "-q"], check=True)
    subprocess.run([TRUEAXIS, "separate", "-i", str(p), "-o", str(r), "--sigma", "0.1", "-q"], check=True)
    subprocess.run([TRUEAXIS, "report", str(r), "-o", str(h), "-q"], check=True)
    dom = dump_dom(h, tmp_path)
    assert 'data-plots-rendered="3"' in dom and 'data-script-errors="' not in dom
    # Axis ticks: sub-micron steps keep their decimals, no "-0", large values no exponent.
    assert evaluate_in(h, tmp_path, "taTicks(null,[-0.0004,-0.0002,-0.0000000001,0.0002],0,0,0.0002)") == \
        ["-0.0004", "-0.0002", "0.0000", "0.0002"]
    assert evaluate_in(h, tmp_path, "taTicks(null,[0,2.5,5],0,0,2.5)") == ["0.0", "2.5", "5.0"]
    assert evaluate_in(h, tmp_path, "taTicks(null,[1000,2000],0,0,1000)") == ["1000", "2000"]


def test_length_report_has_e0_envelope_header_and_csv_in_the_browser(tmp_path):
    # A report a metrologist would sign, as Chromium renders it: the E0 verdict and envelope,
    # the header with the date, the given metadata and k = 2, a CSV link per table and curve,
    # the references, and no script error.
    g, m, t, L, mp, v, h = (str(tmp_path / n) for n in
                            ("g.json", "m.json", "t.csv", "l.csv", "map.json", "v.json", "v.html"))
    subprocess.run([TRUEAXIS, "simulate", "ballgauge", "--noise", "0.5", "--alignment", "ls",
                    "--gauge", g, "--measurements", m, "--truth", t, "--lengths", L, "-q"], check=True)
    subprocess.run([TRUEAXIS, "ballgauge", "--gauge", g, "--measurements", m, "-o", mp, "-q"],
                   check=True)
    subprocess.run([TRUEAXIS, "verify-lengths", "--map", mp, "-i", L, "-o", v, "--report", h,
                    "--mpe", "1.5+L/300", "--meta", "machine=Virtual CMM", "--meta",
                    "operator=K. Tanaka", "-q"], check=True)
    dom = dump_dom(h, tmp_path)
    assert 'data-script-errors="' not in dom
    assert re.search(r'data-plots-rendered="2"', dom)
    assert "E0 envelope" in dom and ">PASS<" in dom and "+MPE" in dom
    assert "<th>machine</th><td>Virtual CMM</td>" in dom
    assert "<th>operator</th><td>K. Tanaka</td>" in dom
    assert re.search(r"<th>date</th><td>\d{4}-\d\d-\d\d", dom)
    assert "k = 2" in dom
    # Each table's CSV is in the page; each plot's is made by the page from the plot's data.
    links = re.findall(r'<a class="csv" download="([^"]+)" href="data:text/csv', dom)
    assert "gauge-block-verification-iso-10360-2-positions-table.csv" in links and len(links) == 3, links
    csvs = plot_csvs(h, tmp_path)
    assert len(csvs) == 2, csvs.keys()
    rows = csvs[0]
    assert rows[0][0] == "nominal length (mm)", rows[0]
    assert rows[0][1:] == ["before correction", "after, grid", "+MPE", "−MPE"], rows[0]
    assert len(rows) > 105 and all(len(r) == len(rows[0]) for r in rows), rows[:3]
    assert all(c == "" or float(c) == float(c) for r in rows[1:] for c in r), rows[:3]
    # Every cell stands under a header that fits it: the E0 verdicts have a table of their own.
    e0 = re.search(r"<h3>E0 against the MPE 1.5\+L/300 µm[^<]*</h3><table>(.*?)</table>", dom, re.S)
    assert e0, "no E0 table"
    rows = [re.findall(r"<t[hd]>([^<]*)</t[hd]>", r) for r in re.findall(r"<tr>(.*?)</tr>", e0.group(1))]
    assert rows[0] == ["E0", "verdict", "lengths beyond the MPE", "worst (% of the MPE)"], rows
    assert rows[1][0] == "before correction" and rows[1][1] in ("PASS", "FAIL"), rows
    assert re.fullmatch(r"\d+ of 105", rows[1][2]) and re.fullmatch(r"\d+", rows[1][3]), rows
    stats = re.search(r'<h2 id="s\d+">Gauge-block verification[^<]*</h2>.*?<table>(.*?)</table>', dom, re.S)
    assert "PASS" not in stats.group(1) and "FAIL" not in stats.group(1)
    assert "105 calibrated lengths in 35 set-ups along 7 lines, ISO 10360-2's positions" in dom
    # The seven positions, each with its direction, its set-ups and its worst error, and every
    # error drawn at its position.
    pos = re.search(r"<h3>Positions \(ISO 10360-2\): the 7 lines the set-ups lie along</h3>"
                    r"<table>(.*?)</table>", dom, re.S)
    assert pos, "no positions table"
    rows = [re.findall(r"<t[hd]>([^<]*)</t[hd]>", r) for r in re.findall(r"<tr>(.*?)</tr>", pos.group(1))]
    assert rows[0] == ["position", "direction", "set-ups", "lengths", "max |E| before (µm)",
                       "max |E| after, grid (µm)"], rows[0]
    assert [r[0] for r in rows[1:]] == [str(k) for k in range(1, 8)]
    directions = [r[1] for r in rows[1:]]
    assert sum(d.startswith("space diagonal (") for d in directions) == 4, directions
    assert {"along X", "along Y", "along Z"} <= set(directions), directions
    assert all(r[2] == "5" and r[3] == "15" for r in rows[1:]), rows
    worst_before = max(float(r[4]) for r in rows[1:])
    table_stats = [re.findall(r"<t[hd]>([^<]*)</t[hd]>", r)
                   for r in re.findall(r"<tr>(.*?)</tr>", stats.group(1))]
    before_row = next(r for r in table_stats if r[0] == "before correction")
    assert worst_before == pytest.approx(max(-float(before_row[1]), float(before_row[2])), abs=0.006)
    by_position = csvs[1]
    assert by_position[0] == ["position", "before correction", "after, grid"], by_position[0]
    xs = [float(r[0]) for r in by_position[1:]]
    assert len(xs) == 2 * 105 and 0.6 < min(xs) and max(xs) < 7.4
    # The section is titled by what it shows, and names the data it was made from.
    assert '<h2 id="s1">Gauge-block verification (ISO 10360-2 positions)</h2>' in dom
    assert '<p class="source">Data: l.csv</p>' in dom
    assert "<h2>References</h2>" in dom and "ISO 10360-2:2009" in dom


def test_scan_report_renders(tmp_path):
    data = os.path.join(os.path.dirname(__file__), "..", "data", "ippdme", "ipp_simple.stp")
    d, p, s, h = (tmp_path / n for n in ("design.json", "part.json", "scan.json", "scan.html"))
    subprocess.run([TRUEAXIS, "design", "--step", data, "--section", "origin=0,0,37.5;normal=0,0,1;name=mid",
                    "-o", str(d), "-q"], check=True)
    subprocess.run([TRUEAXIS, "simulate", "part", "--design", str(d), "--translate", "1.8,-1.1,0",
                    "--bump", "mid.1,150,2,30", "-o", str(p), "-q"], check=True)
    subprocess.run([TRUEAXIS, "scan", "--design", str(d), "--part", str(p), "-o", str(s),
                    "--report", str(h), "--meta", "machine=virtual CMM", "-q"], check=True)
    dom = dump_dom(h, tmp_path)
    total = re.search(r'data-plots-total="(\d+)"', dom)
    rendered = re.search(r'data-plots-rendered="(\d+)"', dom)
    assert total and rendered, "report script did not run"
    assert int(total.group(1)) == 4  # per section: ΔL along each scan, measured − design
    assert rendered.group(1) == total.group(1)
    assert 'data-script-errors="' not in dom, "script errors in the report"
    # Per section: the measured contour coloured by deviation, and the section in its plane
    # (design, corrected design, true part, measured points; deviations magnified).
    assert dom.count('<svg class="ta-fig"') == 4
    assert dom.count("in its plane: deviations from the design") == 2 * 2  # caption, label
    for curve in ("corrected design", "simulated true part", "measured points"):
        assert curve in dom, curve
    assert "trajectory error: scan stopped" in dom  # the stops marked on the ΔL plots
    # Events in words ("design data replaced by the measured contour"), not the log's
    # identifiers ("design_overwritten"); corrections' parameters with their units.
    assert "every decision of the flow" in dom and "design data replaced by the measured contour" in dom
    assert "design_overwritten" not in dom and "trajectory_error" not in dom and "_mm=" not in dom
    assert "virtual CMM" in dom and "JP 6484108 B2" in dom


def test_positioning_report_renders(tmp_path):
    runs, out, h, h2 = (str(tmp_path / n) for n in ("runs.csv", "p.json", "p.html", "p2.html"))
    subprocess.run([TRUEAXIS, "simulate", "positioning", "--targets", "0:50:800", "--backlash", "3",
                    "--noise", "0.4", "--temperature", "21:22", "-o", runs, "-q"], check=True)
    rc = subprocess.run([TRUEAXIS, "positioning", "-i", runs, "-o", out, "--report", h,
                         "--tolerance", "A=50,B=1", "--meta", "axis=X", "-q"],
                        capture_output=True, text=True)
    assert rc.returncode == 1  # B is out of tolerance; the report is written all the same
    subprocess.run([TRUEAXIS, "report", out, "-o", h2, "-q"], check=True)
    for page in (h, h2):
        dom = dump_dom(page, tmp_path)
        assert 'data-script-errors="' not in dom
        # The standard's plot (means with ±2s) and every reading.
        assert 'data-plots-total="2"' in dom and 'data-plots-rendered="2"' in dom
        assert "mean deviations with ±2s" in dom and "every reading" in dom
        assert ">FAIL<" in dom and ">pass<" in dom  # B and A against their tolerances
        assert "ISO 230-2:2014" in dom and "corrected to 20 °C" in dom
        # The page says what its shaded bands are (ISO 230-2's ±2s here, not uncertainties), and
        # the bands' edges are not legend entries of their own.
        assert "Shaded bands: x̄ ± 2s (ISO 230-2" in dom and "standard uncertainties" not in dom
        edges = re.findall(r'<tr class="u-series"[^>]*>(?:(?!</tr>).)*?edge', dom, re.S)
        assert edges and all('display: none' in e for e in edges), edges
        assert '<h2 id="s1">Positioning accuracy of a linear axis</h2>' in dom
    # The axis measured again after its compensation, compared with this run on one plot.
    comp, runs2, out2, h3 = (str(tmp_path / n) for n in ("x.comp", "r2.csv", "p2.json", "p3.html"))
    subprocess.run([TRUEAXIS, "export", "linuxcnc", "--positioning", out, "-o", comp, "-q"],
                   check=True)
    subprocess.run([TRUEAXIS, "simulate", "positioning", "--targets", "0:40:800", "--backlash", "3",
                    "--noise", "0.4", "--compensation", comp, "--seed", "2", "-o", runs2, "-q"],
                   check=True)
    shown = subprocess.run([TRUEAXIS, "positioning", "-i", runs2, "-o", out2, "--report", h3,
                            "--before", out],
                           capture_output=True, text=True, check=True).stdout
    a_before, a_after = map(float, re.search(r"before compensation \([^)]*\): A ([0-9.]+) -> "
                                             r"([0-9.]+) µm", shown).groups())
    assert a_after < a_before / 2, shown
    dom = dump_dom(h3, tmp_path)
    assert 'data-plots-total="3"' in dom and 'data-plots-rendered="3"' in dom
    assert f"<h3>before and after compensation — A {a_before:.2f} µm → {a_after:.2f} µm" in dom
    for label in ("x̄↑ ± 2s↑ before", "x̄↓ ± 2s↓ before", "x̄↑ ± 2s↑ after", "x̄↓ ± 2s↓ after"):
        assert f">{label}<" in dom, label
    # Targets of one run missing from the other (0:40 against 0:50) are spanned, not gaps.
    spans = evaluate_in(h3, tmp_path, "TA_PLOTS[2].series.slice(1).map(function(s){return !!s.spanGaps;})")
    assert spans == [True] * 4
    bad = subprocess.run([TRUEAXIS, "positioning", "-i", runs2, "-o", str(tmp_path / "x.json"),
                          "--before", str(tmp_path / "p.html")], capture_output=True, text=True)
    assert bad.returncode != 0 and "p.html" in bad.stderr
    # Printable: the print stylesheet hides what only a screen uses; Chromium prints it to PDF.
    text = open(h, encoding="utf-8").read()
    assert "@media print{" in text and ".screen," in text
    pdf = tmp_path / "p.pdf"
    subprocess.run([chromium(), "--headless", "--no-sandbox", "--disable-gpu", "--no-first-run",
                    f"--user-data-dir={tmp_path / 'profile-pdf'}", "--virtual-time-budget=5000",
                    f"--print-to-pdf={pdf}", f"file://{h}"], capture_output=True, timeout=120)
    data = pdf.read_bytes()
    assert data.startswith(b"%PDF") and len(re.findall(rb"/Type\s*/Page\b", data)) >= 1


def test_ballgauge_map_tables_hold_only_what_their_headers_say(tmp_path):
    g, m, t, mp, mo, h = (str(tmp_path / n) for n in ("g.json", "m.json", "t.csv", "map.json",
                                                      "model.json", "map.html"))
    subprocess.run([TRUEAXIS, "simulate", "ballgauge", "--noise", "0.3", "--alignment", "ls",
                    "--gauge", g, "-o", m, "--truth", t, "-q"], check=True)
    subprocess.run([TRUEAXIS, "ballgauge", "--gauge", g, "--measurements", m, "-o", mp,
                    "--parametric", mo, "--stylus-offset", "0,0,-100", "--report", h, "-q"],
                   check=True)
    dom = dump_dom(h, tmp_path)
    assert 'data-script-errors="' not in dom
    tables = re.findall(r"(?:<h3>([^<]*)</h3>)?<table>(.*?)</table>", dom, re.S)
    cells = {cap: [re.findall(r"<t[hd]>([^<]*)</t[hd]>", r) for r in re.findall(r"<tr>(.*?)</tr>", body)]
             for cap, body in tables}
    placements = next(rows for rows in cells.values() if rows and rows[0][0] == "placement")
    assert [r[0] for r in placements[1:]] == ["placement 1", "placement 2", "placement 3"], placements
    square = cells["Squareness of the axes (ISO 230-1)"]
    assert square[0] == ["error", "value (µrad)", "U (µrad, k = 2)"]
    assert [r[0] for r in square[1:]] == ["EC0Y", "EB0Z", "EA0Z"]
    assert all(re.fullmatch(r"-?\d+\.\d\d", c) for r in square[1:] for c in r[1:]), square
    model = next(rows for cap, rows in cells.items() if cap.startswith("Parametric model"))
    assert model[0][0] == "degree" and re.fullmatch(r"\d+ / \d+", model[1][2]), model


def test_guideway_straightness_is_drawn_with_the_line_its_pv_is_about(tmp_path):
    subprocess.run([TRUEAXIS, "examples", "-o", str(tmp_path), "-q"], check=True)
    spots, out, h = (str(tmp_path / n) for n in ("spots.csv", "g.json", "g.html"))
    subprocess.run([TRUEAXIS, "simulate", "guideway5d", "--layout", str(tmp_path / "layout.json"),
                    "--axis", "x", "--noise", "0.2", "-o", spots, "-q"], check=True)
    subprocess.run([TRUEAXIS, "guideway", "--layout", str(tmp_path / "layout.json"), "--input", spots,
                    "-o", out, "--report", h, "-q"], check=True)
    dom = dump_dom(h, tmp_path)
    assert 'data-script-errors="' not in dom
    for name in ("horizontal", "vertical"):
        pv = re.search(rf"<td>{name}</td><td>yes</td><td>([^<]*)</td>", dom).group(1)
        title = re.search(rf"<h3>{name} straightness[^<]*PV about the least-squares line ([^<]*)</h3>",
                          dom)
        assert title and title.group(1) == pv, (name, pv, title and title.group(0))
    assert dom.count("least-squares line") >= 4  # two titles, two legend entries
    # The zone's two lines under one legend entry; a stand-alone carriage's own error names.
    assert dom.count(">minimum zone<") == 2
    upper = re.findall(r'<tr class="u-series"[^>]*>(?:(?!</tr>).)*?minimum zone, upper line', dom, re.S)
    assert len(upper) == 2 and all('display: none' in e for e in upper), upper
    assert "EYX" not in dom
    # On the machine's X axis the errors carry ISO 230-1's names, in the machine frame.
    out2, h2 = str(tmp_path / "gx.json"), str(tmp_path / "gx.html")
    shown = subprocess.run([TRUEAXIS, "guideway", "--layout", str(tmp_path / "layout.json"),
                            "--input", spots, "--axis", "X", "-o", out2, "--report", h2],
                           capture_output=True, text=True, check=True).stdout
    for name in ("EYX (horizontal)", "EZX (vertical)", "EBX (pitch)", "ECX (yaw)", "EAX (roll)"):
        assert name in shown, shown
    dom = dump_dom(h2, tmp_path)
    assert 'data-script-errors="' not in dom
    names = re.findall(r"<tr><td>(E[XYZABC]X \([a-z]+\))</td>", dom)
    assert names == ["EYX (horizontal)", "EZX (vertical)", "EBX (pitch)", "ECX (yaw)", "EAX (roll)"], names
    assert re.search(r"<h3>EYX horizontal straightness — PV about the least-squares line", dom)
    assert json.load(open(out2))["axis"] == "X"
    subprocess.run([TRUEAXIS, "report", out2, "-o", str(tmp_path / "gx2.html"), "-q"], check=True)
    assert "<td>EAX (roll)</td>" in open(tmp_path / "gx2.html", encoding="utf-8").read()


def test_records_trend_report_and_certificate_render_and_print(tmp_path):
    # The demo's three yearly visits: the backlash trend over dates, and the last certificate.
    demo = tmp_path / "demo"
    subprocess.run([TRUEAXIS, "demo", "-o", str(demo / "index.html"), "-q"], check=True)
    db, trend = str(demo / "records.db"), tmp_path / "trend.html"
    subprocess.run([TRUEAXIS, "record", "trend", "--db", db, "--machine", "DEMO-VMC", "--figure",
                    "B", "--axis", "x", "--tolerance", "6", "--report", str(trend), "-q"],
                   check=True)
    dom = dump_dom(trend, tmp_path)
    assert 'data-plots-total="1"' in dom and 'data-plots-rendered="1"' in dom
    assert 'data-script-errors="' not in dom
    # The x axis holds dates (a time scale in seconds, the days at midnight UTC) and the CSV's
    # first column ISO dates.
    x = evaluate_in(trend, tmp_path, "[TA_PLOTS[0].xd, TA_PLOTS[0].data[0]]")
    assert x[0] is True and 1736899200 in x[1], x  # 2025-01-15T00:00Z, the first visit
    rows = plot_csvs(trend, tmp_path)[0]
    assert rows[0][:3] == ["date", "as found", "as left"], rows[0]
    assert all(re.fullmatch(r"\d{4}-\d{2}-\d{2}", r[0]) for r in rows[1:]), rows[:3]
    assert "2025-01-15" in [r[0] for r in rows]  # the first visit, on its own day in any zone
    # The certificate: every section there, no script error, printed to PDF pages.
    cert = demo / "certificate.html"
    dom = dump_dom(cert, tmp_path)
    assert 'data-script-errors="' not in dom
    for title in ("Certificate", "Instruments and their calibration", "Results as found",
                  "Results as left", "Decision rule", "Signatures"):
        assert re.search(f">{re.escape(title)}[^<]*</h2>", dom), title
    pdf = tmp_path / "cert.pdf"
    subprocess.run([chromium(), "--headless", "--no-sandbox", "--disable-gpu", "--no-first-run",
                    f"--user-data-dir={tmp_path / 'profile-pdf'}", "--virtual-time-budget=5000",
                    f"--print-to-pdf={pdf}", f"file://{cert}"], capture_output=True, timeout=120)
    data = pdf.read_bytes()
    assert data.startswith(b"%PDF") and len(re.findall(rb"/Type\s*/Page\b", data)) >= 2
