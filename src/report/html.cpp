#include "trueaxis/report/html.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string_view>

#include "../common/figures.hpp"
#include "../io/fast_text.hpp"
#include "trueaxis/error.hpp"
#include "trueaxis/geometry/straightness.hpp"

namespace trueaxis::report {
namespace detail {
extern const std::string_view kUplotJs;
extern const std::string_view kUplotCss;
}  // namespace detail

namespace {

const char* kPalette[] = {"#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#17becf"};

// Indices kept for display: all, or per bucket the first, min and max of the first series.
std::vector<Eigen::Index> decimate(const Plot& p, std::size_t max_points) {
  const Eigen::Index n = p.x.size();
  std::vector<Eigen::Index> idx;
  if (static_cast<std::size_t>(n) <= max_points || p.series.empty()) {
    for (Eigen::Index i = 0; i < n; ++i) idx.push_back(i);
    return idx;
  }
  const Eigen::Index buckets = static_cast<Eigen::Index>(max_points / 2);
  const Eigen::VectorXd& y = p.series.front().y;
  for (Eigen::Index b = 0; b < buckets; ++b) {
    const Eigen::Index lo = b * n / buckets, hi = std::max(lo + 1, (b + 1) * n / buckets);
    Eigen::Index imin = lo, imax = lo;
    for (Eigen::Index i = lo; i < hi; ++i) {
      if (y[i] < y[imin]) imin = i;
      if (y[i] > y[imax]) imax = i;
    }
    idx.push_back(std::min(imin, imax));
    if (imin != imax) idx.push_back(std::max(imin, imax));
  }
  // The ends always: where a series given only at its ends (a reference line) is drawn.
  if (idx.front() != 0) idx.insert(idx.begin(), 0);
  if (idx.back() != n - 1) idx.push_back(n - 1);
  return idx;
}

// Values with `digits` significant digits: 6 for positions (1 µm at 999 mm), 5 for the plotted
// quantities (0.1 nm in 1 µm: finer than a plot shows, or than the numbers' uncertainty).
void js_array(std::string& out, const Eigen::VectorXd& v, const std::vector<Eigen::Index>& idx,
              int digits = 5) {
  out += '[';
  for (std::size_t k = 0; k < idx.size(); ++k) {
    if (k) out += ',';
    const double val = v[idx[k]];
    if (std::isfinite(val))
      out += fmt::format("{:.{}g}", val, digits);
    else if (k + 1 == idx.size())
      out += "null";  // a hole at the end would not count: [1,] has one element
    // A missing value is a hole ([1,,3]), which the page reads as null: series drawn over part
    // of a shared x are mostly holes.
  }
  out += ']';
}

// A JavaScript string literal (JSON rules; '<' escaped so "</script>" cannot end the block).
std::string js_string(const std::string& t) {
  std::string o = "\"";
  for (unsigned char c : t) {
    if (c == '"' || c == '\\') {
      o += '\\';
      o += static_cast<char>(c);
    } else if (c == '<') {
      o += "\\u003c";
    } else if (c < 0x20) {
      o += fmt::format("\\u{:04x}", c);
    } else {
      o += static_cast<char>(c);
    }
  }
  return o + "\"";
}

}  // namespace

std::string escape(const std::string& s) {
  std::string o;
  for (char c : s) {
    switch (c) {
      case '<':
        o += "&lt;";
        break;
      case '>':
        o += "&gt;";
        break;
      case '&':
        o += "&amp;";
        break;
      case '"':
        o += "&quot;";
        break;
      default:
        o += c;
    }
  }
  return o;
}

namespace {

// A link that downloads `csv` as `name` (a data: URI; works offline, needs no script).
std::string csv_link(const std::string& name, const std::string& csv) {
  std::string href = "data:text/csv;charset=utf-8,";
  href.reserve(href.size() + csv.size() * 3);
  static const char* hex = "0123456789ABCDEF";
  for (unsigned char c : csv) {
    if (std::isalnum(c) || c == '-' || c == '.' || c == '_' || c == ',')
      href += static_cast<char>(c);
    else {
      href += '%';
      href += hex[c >> 4];
      href += hex[c & 15];
    }
  }
  return "<a class=\"csv\" download=\"" + escape(name) + "\" href=\"" + href + "\">CSV</a>";
}

std::string csv_cell(const std::string& s) {
  if (s.find_first_of(",\"\n") == std::string::npos) return s;
  std::string q(1, '"');
  for (char c : s) {
    q.push_back(c);
    if (c == '"') q.push_back('"');
  }
  q.push_back('"');
  return q;
}

std::string slug(const std::string& s) {
  std::string o;
  for (unsigned char c : s) {
    if (std::isalnum(c))
      o += static_cast<char>(std::tolower(c));
    else if (!o.empty() && o.back() != '-')
      o += '-';
  }
  while (!o.empty() && o.back() == '-') o.pop_back();
  return o.substr(0, 60);
}

}  // namespace

std::string render(const std::string& title, const std::vector<Section>& sections,
                   std::size_t max_points, const Meta& meta) {
  std::string h;
  h += "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\n<title>" +
       escape(title) + "</title>\n<style>";
  h += detail::kUplotCss;
  h += R"CSS(
body{font-family:system-ui,-apple-system,Segoe UI,Roboto,sans-serif;margin:24px auto;max-width:1100px;color:#222;padding:0 16px}
h1{font-size:1.6em} h2{border-bottom:1px solid #ddd;padding-bottom:4px;margin-top:2em}
table{border-collapse:collapse;margin:8px 0;display:block;max-width:100%;overflow-x:auto} td,th{border:1px solid #ccc;padding:3px 8px;text-align:right}
th{background:#f4f4f4} td:first-child,th:first-child{text-align:left}
.plot{margin:16px 0} .plot h3{font-size:1em;margin:4px 0}
.note{color:#666;font-size:.9em} .source{color:#444;margin:-4px 0 8px;font-size:.95em}
.meta th{text-align:left;background:#f8f8f8} .dl{margin:2px 0 10px;font-size:.85em}
.warn{background:#fff4e5;border-left:4px solid #e08a00;padding:6px 10px;margin:8px 0}
.figs{display:flex;flex-wrap:wrap;gap:16px;align-items:flex-start;margin:12px 0}
.figs figure{margin:0} .figs figcaption{font-weight:600;font-size:.95em;margin:4px 0}
svg.ta-fig{max-width:100%;height:auto}
.toc ol{padding-left:1.6em} .toc li{margin:2px 0} .toc .flag{color:#a65c00}
@media print{
 body{margin:0;max-width:none;font-size:10pt;padding:0}
 .screen,a.csv,.u-select,.u-cursor-x,.u-cursor-y{display:none!important}
 h2{break-after:avoid} h3{break-after:avoid}
 figure,.plot,tr{break-inside:avoid}
 table{display:table;overflow:visible;font-size:8pt} td,th{padding:1px 4px}
 td{white-space:nowrap} td.txt{white-space:normal;min-width:14em}
 table.wide{font-size:6.5pt} table.wide td,table.wide th{padding:0 2px}
 .u-legend{font-size:8pt} .u-legend .u-value{display:none}
 .u-legend .u-series:first-child{display:none}
}
)CSS";
  h += "</"
       "style>\n<script>window.__taErrors=[];window.addEventListener('error',function(e){window.__"
       "taErrors.push(String(e.message));document.documentElement.setAttribute('data-script-errors'"
       ",window.__taErrors.length);});</script>\n<script>";
  h += detail::kUplotJs;
  h += "</script>\n</head><body>\n<h1>" + escape(title) + "</h1>\n";
  // Say only what the page has: zoomable plots, and what each kind of shaded band is.
  bool plots = false;
  std::vector<std::string> bands;
  for (const auto& sec : sections)
    for (const auto& p : sec.plots) {
      plots = true;
      for (const auto& ser : p.series)
        if (ser.band.size() > 0 &&
            std::find(bands.begin(), bands.end(), ser.band_meaning) == bands.end())
          bands.push_back(ser.band_meaning);
    }
  h += std::string("<p class=\"note\">") +
       (plots ? "<span class=\"screen\">Drag across a plot to zoom, double-click to reset. </span>"
              : "") +
       (bands.empty() ? std::string() : fmt::format("Shaded bands: {}. ", fmt::join(bands, "; "))) +
       "Generated by trueaxis.</p>\n";
  {
    // The header: what, when, on what, by whom, and the coverage factor of every stated U.
    const std::time_t now = std::time(nullptr);
    char date[64];
    std::strftime(date, sizeof date, "%Y-%m-%d %H:%M UTC", std::gmtime(&now));
    h += "<table class=\"meta\"><tr><th>date</th><td>" + std::string(date) + "</td></tr>";
    for (const auto& [k, v] : meta)
      h += "<tr><th>" + escape(k) + "</th><td>" + escape(v) + "</td></tr>";
    h += "<tr><th>coverage factor</th><td>k = 2 for expanded uncertainties (U = 2u) and "
         "bands, about 95 %</td></tr></table>\n";
  }
  // A report of several sections opens with its contents: each section's title as a link and
  // its headline figure.
  if (sections.size() >= 3) {
    h += "<nav class=\"toc\"><h2>Contents</h2><ol>";
    for (std::size_t i = 0; i < sections.size(); ++i) {
      const auto& s = sections[i];
      h += fmt::format("<li><a href=\"#s{}\">{}</a>", i + 1, escape(s.title));
      if (!s.summary.empty()) h += ": " + escape(s.summary);
      if (!s.warnings.empty())
        h += fmt::format(" <span class=\"flag\">({} warning{})</span>", s.warnings.size(),
                         s.warnings.size() > 1 ? "s" : "");
      h += "</li>";
    }
    h += "</ol></nav>\n";
  }
  std::string script = "var TA_PLOTS=[];\n";
  int pid = 0, figures = 0, sid = 0;
  for (const auto& s : sections) {
    h += fmt::format("<h2 id=\"s{}\">{}</h2>\n", ++sid, escape(s.title));
    if (!s.source.empty()) h += "<p class=\"source\">Data: " + escape(s.source) + "</p>\n";
    for (const auto& w : s.warnings)
      h += "<p class=\"warn\"><b>Warning:</b> " + escape(w) + "</p>\n";
    h += s.intro_html + "\n";
    using Tables = std::vector<std::pair<std::string, std::vector<std::vector<std::string>>>>;
    Tables tables;
    if (!s.table.empty()) tables.emplace_back("", s.table);
    for (const auto& t : s.more_tables) tables.push_back(t);
    auto emit_tables = [&](const Tables& list) {
      for (std::size_t ti = 0; ti < list.size(); ++ti) {
        const auto& [caption, table] = list[ti];
        if (!caption.empty()) h += "<h3>" + escape(caption) + "</h3>";
        // Printed, a table fits the page's width: one of many columns (Moody's worksheet) in a
        // smaller type, a cell of prose wrapping, a value never.
        std::size_t columns = 0;
        for (const auto& row : table) columns = std::max(columns, row.size());
        h += columns > 12 ? "<table class=\"wide\">" : "<table>";
        for (std::size_t r = 0; r < table.size(); ++r) {
          h += "<tr>";
          for (const auto& c : table[r]) {
            const bool prose = r > 0 && c.size() > 40 && c.find(' ') != std::string::npos;
            h += (r == 0  ? "<th>"
                  : prose ? "<td class=\"txt\">"
                          : "<td>") +
                 escape(c) + (r == 0 ? "</th>" : "</td>");
          }
          h += "</tr>";
        }
        h += "</table>\n";
        std::string csv;
        for (const auto& row : table) {
          for (std::size_t c = 0; c < row.size(); ++c) {
            if (c) csv.push_back(',');
            csv.append(csv_cell(row[c]));
          }
          csv += "\n";
        }
        const std::string name =
            slug(s.title) + (ti == 0 && caption.empty() ? "-table" : "-" + slug(caption)) + ".csv";
        h += "<p class=\"dl\">" + csv_link(name, csv) + "</p>\n";
      }
    };
    emit_tables(tables);
    for (const auto& p : s.plots) {
      const std::string id = fmt::format("plot{}", pid++);
      h += "<div class=\"plot\"><h3>" + escape(p.title) + "</h3><div id=\"" + id + "\"></div>";
      const auto idx = decimate(p, max_points);
      const bool all = idx.size() == static_cast<std::size_t>(p.x.size());
      if (!all)
        h += fmt::format("<p class=\"note\">{} of {} points shown (min/max per bucket).</p>",
                         idx.size(), p.x.size());
      // The figure's numbers as CSV, made by the page from the plot's own data when asked for
      // (x, each series and its standard uncertainty u): the report carries them once.
      h += fmt::format(
          "<p class=\"dl\"><a class=\"csv\" href=\"#\" download=\"{}.csv\" "
          "data-plot=\"{}\">CSV</a>{}"
          "</p>",
          escape(slug(p.title)), pid - 1,
          all ? "" : " (the points drawn; every point is in the result file)");
      h += "</div>\n";
      std::string data = "[";
      js_array(data, p.x, idx, 6);
      std::string series = "[{label:" + js_string(p.x_label) + "}";
      std::string u = "{";
      int col = 0, si = 1;
      // Scatter plots pad the x range, so that markers at the ends (several at one x, as
      // repeated readings at the last target) are drawn whole.
      const bool scatter =
          std::any_of(p.series.begin(), p.series.end(), [](const Series& q) { return q.points; });
      for (const auto& s2 : p.series) {
        const std::string color = s2.color.empty() ? kPalette[col++ % 6] : s2.color;
        data += ',';
        js_array(data, s2.y, idx);
        if (s2.points)
          series += fmt::format(
              ",{{label:{},stroke:'{}',fill:'{}',width:1,paths:function(){{return null;}},"
              "points:{{show:true,size:7,width:1,stroke:'{}',fill:'{}88'}}}}",
              js_string(s2.label), color, color, color, color);
        else
          series +=
              fmt::format(",{{label:{},stroke:'{}',width:1.5{}{}{}{}}}", js_string(s2.label), color,
                          s2.dashed ? ",dash:[6,4]" : "", p.span_gaps ? ",spanGaps:true" : "",
                          s2.in_legend ? "" : ",edge:true",
                          // A line over dates is sampled for its shape: its samples are not data.
                          p.x_dates ? ",points:{show:false}" : "");
        // The ±2u band: u here, its edges made by the page (below).
        if (s2.band.size() == s2.y.size()) {
          u += fmt::format("{}:", si);
          js_array(u, s2.band, idx);
          u += ',';
        }
        ++si;
      }
      data += "]";
      series += "]";
      u += "}";
      script += fmt::format(
          "TA_PLOTS.push({{el:'{}',data:{},u:{},series:{},xl:{},yl:{},log:{},pts:{}{}{}}});\n", id,
          data, u, series, js_string(p.x_label), js_string(p.y_label), p.log_y ? "true" : "false",
          scatter ? "true" : "false", p.whole_x ? ",wx:true" : "", p.x_dates ? ",xd:true" : "");
    }
    if (!s.views.empty() || !s.heat_maps.empty() || !s.grids.empty() || !s.planes.empty()) {
      h += "<div class=\"figs\">";
      auto figure = [&](const std::string& title, const std::string& body) {
        h += "<figure><figcaption>" + escape(title) + "</figcaption>" + body + "</figure>\n";
        ++figures;
      };
      for (const auto& v : s.views) figure(v.title, svg(v));
      for (const auto& m : s.heat_maps) figure(m.title, svg(m));
      for (const auto& g : s.grids) figure(g.title, svg(g));
      for (const auto& v : s.planes) figure(v.title, svg(v));
      h += "</div>\n";
    }
    emit_tables(s.tables_after);
  }
  // One list of the sources the sections' methods follow, each once, in order of first use.
  std::vector<std::string> refs;
  for (const auto& s : sections)
    for (const auto& r : s.references)
      if (std::find(refs.begin(), refs.end(), r) == refs.end()) refs.push_back(r);
  if (!refs.empty()) {
    h += "<h2>References</h2>\n<ol class=\"refs\">";
    for (const auto& r : refs) h += "<li>" + escape(r) + "</li>";
    h += "</ol>\n";
  }
  script += fmt::format("var TA_FIGURES={};\n", figures);
  h += "<script>\n" + script + R"JS(
// Tick labels with as many decimals as the step needs ("0.0002", not "0", "-0"), no "-0".
function taTicks(u,splits,ax,space,incr){
  var d=Math.max(0,Math.ceil(-Math.log10(incr)-1e-9));
  while(d<12&&Math.abs(incr*Math.pow(10,d)-Math.round(incr*Math.pow(10,d)))>1e-6*incr*Math.pow(10,d))d++;
  return splits.map(function(v){
    if(v==null)return '';
    var t=v.toFixed(d);
    return /^-0(\.0*)?$/.test(t)?t.slice(1):t;
  });
}
// A y axis as wide as its longest tick label, and room for its title.
function taAxisSize(u,values){
  var n=0;(values||[]).forEach(function(v){n=Math.max(n,String(v).length);});
  return Math.max(50,7*n+34);
}
(function(){
  var made=0;
  // Holes in the data ([1,,3]) are missing values: null, as the plots and the CSV want them.
  function filled(a){return Array.from(a,function(v){return v===undefined?null:v;});}
  TA_PLOTS.forEach(function(p){
    p.data=p.data.map(filled);
    Object.keys(p.u).forEach(function(k){p.u[k]=filled(p.u[k]);});
    // Dates: days since 1970 as the seconds a time axis counts.
    if(p.xd)p.data[0]=p.data[0].map(function(d){return d===null?null:d*86400;});
  });
  TA_PLOTS.forEach(function(p){
    var el=document.getElementById(p.el);
    var w=Math.max(400,Math.min(1060,(document.body.clientWidth||900)-20));
    // Each series with a u gets its band y ± 2u: two faint edges (out of the legend: the
    // series' own label names the band) and the fill between them.
    var data=p.data.slice(),series=p.series.slice(),bands=[];
    Object.keys(p.u).forEach(function(k){
      var i=+k,y=p.data[i],u=p.u[k],c=p.series[i].stroke;
      var up=y.map(function(v,j){return v===null||u[j]===null?null:v+2*u[j];});
      var lo=y.map(function(v,j){return v===null||u[j]===null?null:v-2*u[j];});
      data.push(up,lo);
      var g=!!p.series[i].spanGaps;
      var edge=function(l){var e={label:p.series[i].label+l,stroke:c+'44',width:0.5,edge:true,spanGaps:g};
        if(p.xd)e.points={show:false};return e;};
      series.push(edge(' upper edge'),edge(' lower edge'));
      bands.push({series:[data.length-2,data.length-1],fill:c+'22'});
    });
    var pad=function(u,mn,mx){var d=(mx-mn)*0.03||1;return [mn-d,mx+d];};
    var opts={width:w,height:300,series:series,bands:bands,
      // Dates in UTC, the day each was recorded, wherever the report is read.
      tzDate:function(ts){return uPlot.tzDate(new Date(ts*1e3),'Etc/UTC');},
      scales:{x:p.xd?(p.pts?{time:true,range:pad}:{time:true}):p.pts?{time:false,range:pad}:{time:false},
              y:p.log?{distr:3}:{}},
      axes:[p.xd?{label:p.xl}:p.wx?{label:p.xl,values:taTicks,incrs:[1,2,5,10,20,50,100,200,500,1000]}:{label:p.xl,values:taTicks},
            p.log?{label:p.yl,size:70}:{label:p.yl,values:taTicks,size:taAxisSize}],
      cursor:{drag:{x:true,y:false}}};
    var u=new uPlot(opts,data,el);
    var rows=el.querySelectorAll('.u-legend .u-series');
    series.forEach(function(s,i){if(s.edge&&rows[i])rows[i].style.display='none';});
    if(el.querySelector('canvas')) made++;
  });
  // A plot's CSV link: its numbers (x, each series, u where it has one), made when clicked.
  function cell(t){t=String(t);return /[",\n]/.test(t)?'"'+t.replace(/"/g,'""')+'"':t;}
  document.querySelectorAll('a[data-plot]').forEach(function(a){
    a.addEventListener('click',function(){
      var p=TA_PLOTS[+a.getAttribute('data-plot')],cols=[0],head=[cell(p.series[0].label)];
      for(var i=1;i<p.series.length;i++){
        cols.push(i);head.push(cell(p.series[i].label));
        if(p.u[i]){cols.push(-i);head.push(cell(p.series[i].label+' u'));}
      }
      var lines=[head.join(',')];
      for(var j=0;j<p.data[0].length;j++)
        lines.push(cols.map(function(c){var v=c<0?p.u[-c][j]:p.data[c][j];
          if(v!==null&&c===0&&p.xd)return new Date(v*1000).toISOString().slice(0,10);
          return v===null?'':v;}).join(','));
      a.href=URL.createObjectURL(new Blob([lines.join('\n')+'\n'],{type:'text/csv'}));
    });
  });
  document.documentElement.setAttribute('data-plots-total',TA_PLOTS.length);
  document.documentElement.setAttribute('data-plots-rendered',made);
  document.documentElement.setAttribute('data-figures-total',TA_FIGURES);
})();
</script>
</body></html>
)JS";
  return h;
}

void write(const std::string& path, const std::string& html) {
  io::detail::OutFile out(path);
  out.write(html);
  out.close();
}

void add_reference_lines(Plot& p, const Eigen::VectorXd& x, const Eigen::VectorXd& y,
                         double scale) {
  const geometry::Line ls = geometry::fit_line(x, y);
  const geometry::MinZone mz = geometry::min_zone(x, y);
  // The zone's width is perpendicular to its lines; along y its half-height is larger by
  // √(1 + slope²).
  const double half = mz.width / 2 * std::sqrt(1 + mz.middle.slope * mz.middle.slope);
  // Straight lines: their two ends carry them (the page spans the gaps between), so a long
  // profile does not carry three more series of its length.
  const double nan = std::numeric_limits<double>::quiet_NaN();
  Eigen::VectorXd line = Eigen::VectorXd::Constant(x.size(), nan), lower = line, upper = line;
  Eigen::Index first = 0, last = 0;
  x.minCoeff(&first);
  x.maxCoeff(&last);
  for (const Eigen::Index i : {first, last}) {
    line[i] = ls(x[i]) * scale;
    // A negative scale (a value shown with the opposite sign) swaps the two lines.
    lower[i] = (mz.middle(x[i]) - (scale < 0 ? -half : half)) * scale;
    upper[i] = (mz.middle(x[i]) + (scale < 0 ? -half : half)) * scale;
  }
  p.span_gaps = true;
  p.series.push_back({"least-squares line", line, {}, "#444444", true});
  p.series.push_back({"minimum zone", lower, {}, "#2ca02c", true});
  Series up{"minimum zone, upper line", upper, {}, "#2ca02c", true};
  up.in_legend = false;
  p.series.push_back(std::move(up));
}

Section separation_section(const std::string& title, const separation::Result& r,
                           const separation::Result* truth) {
  Section s;
  s.title = title;
  s.references = {refs::kThreePoint, refs::kIso12780, refs::kIso16610, refs::kGum};
  std::string unobs;
  for (const auto& u : r.unobservable) unobs += (unobs.empty() ? "" : ", ") + u;
  s.warnings = r.warnings();
  s.intro_html = fmt::format(
      "<p>Method <b>{}</b>, reference <b>{}</b>. {}.<br>Not determined by the data: {}.</p>",
      escape(separation::to_string(r.method)), escape(separation::to_string(r.reference)),
      escape(r.gauge), escape(unobs));
  // Each figure beside its expanded uncertainty; one the data cannot resolve is not shown as a
  // number, and one without an uncertainty says so.
  s.table.push_back({"profile", "LS straightness (µm)", "min-zone straightness (µm)",
                     "U (µm, 95 %)", "max u (µm)"});
  auto row = [&](const char* name, const separation::Straightness& st,
                 const separation::Profile& p) {
    const std::string maxu = p.uncertainty.size()
                                 ? trueaxis::detail::two_digits(p.uncertainty.maxCoeff() * 1e3)
                                 : std::string("-");
    if (st.U && !*st.resolved())
      return std::vector<std::string>{name, "not resolved", "not resolved",
                                      trueaxis::detail::two_digits(*st.U * 1e3), maxu};
    if (st.U)
      return std::vector<std::string>{name, trueaxis::detail::rounded_to(st.ls * 1e3, *st.U * 1e3),
                                      trueaxis::detail::rounded_to(st.min_zone * 1e3, *st.U * 1e3),
                                      trueaxis::detail::two_digits(*st.U * 1e3), maxu};
    return std::vector<std::string>{name, fmt::format("{:.4g}", st.ls * 1e3),
                                    fmt::format("{:.4g}", st.min_zone * 1e3), "not stated", maxu};
  };
  s.table.push_back(row("workpiece", r.workpiece_straightness, r.workpiece));
  s.table.push_back(row("guide", r.guide_straightness, r.guide));
  if (!r.no_uncertainty.empty())
    s.intro_html += fmt::format("<p>No uncertainty is stated: {}.</p>", escape(r.no_uncertainty));
  if (truth) {
    auto err = [](const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
      return a.size() == b.size() ? fmt::format("{:.3g}", (a - b).cwiseAbs().maxCoeff() * 1e3)
                                  : std::string("-");
    };
    s.table.push_back({"max |separated − true| workpiece (µm)",
                       err(r.workpiece.value, truth->workpiece.value), "", "", ""});
    s.table.push_back(
        {"max |separated − true| guide (µm)", err(r.guide.value, truth->guide.value), "", "", ""});
  }
  auto plot = [&](const char* name, const separation::Profile& p, const separation::Profile* t,
                  double scale, const char* unit, bool straightness) {
    Plot pl;
    pl.title = name;
    pl.x_label = "x (mm)";
    pl.y_label = fmt::format("{} ({})", name, unit);
    pl.x = p.x;
    Series a{"separated", p.value * scale,
             p.uncertainty.size() ? Eigen::VectorXd(p.uncertainty * scale) : Eigen::VectorXd(), "",
             false};
    pl.series.push_back(a);
    // Straightness figures are about these lines (ISO 12780-1): drawn with the profile.
    if (straightness && p.x.size() >= 2) add_reference_lines(pl, p.x, p.value, scale);
    if (t && t->value.size() == p.value.size())
      pl.series.push_back({"true", t->value * scale, {}, "#d62728", true});
    s.plots.push_back(std::move(pl));
  };
  plot("workpiece", r.workpiece, truth ? &truth->workpiece : nullptr, 1e3, "µm", true);
  plot("guide straightness", r.guide, truth ? &truth->guide : nullptr, 1e3, "µm", true);
  if (r.pitch)
    plot("pitch", *r.pitch, truth && truth->pitch ? &*truth->pitch : nullptr, 1e6, "µrad", false);
  return s;
}

}  // namespace trueaxis::report
