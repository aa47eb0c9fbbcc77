"""The report page: one self-contained HTML file (plotly.js, the figures' data, the model
drawing as SVG and the PNGs embedded), which opens offline in any browser.

The page marks itself when its figures are drawn: ``<body data-rendered="N"
data-figures="M" data-errors="..." data-requests="...">`` (figures drawn, figures on the
page, script errors, resources it asked for: what the headless-browser test reads).
"""

from __future__ import annotations

import base64
import datetime
import html
import io
from typing import Any

import plotly.io as pio
from plotly.offline import get_plotlyjs

from .. import __version__

__all__ = ["Page"]

CSS = """
body{font-family:system-ui,-apple-system,"Segoe UI",Roboto,Arial,sans-serif;margin:0;
color:#1d2329;background:#f6f7f9}
header{background:#1d3557;color:#fff;padding:18px 32px}
header h1{margin:0;font-size:1.5em}header p{margin:4px 0 0;opacity:.85}
nav{background:#fff;border-bottom:1px solid #dde;padding:8px 32px;position:sticky;top:0;
z-index:10}nav a{margin-right:16px;color:#1d3557;text-decoration:none;font-size:.92em}
main{max-width:1200px;margin:0 auto;padding:16px 32px 48px}
section{background:#fff;border:1px solid #e1e4e8;border-radius:6px;padding:12px 20px;
margin:16px 0}h2{font-size:1.2em;margin:4px 0 12px;color:#1d3557}
table{border-collapse:collapse;margin:8px 0 12px;font-size:.9em}
th,td{border:1px solid #d0d7de;padding:4px 8px;text-align:left;vertical-align:top}
th{background:#eef1f4}td{font-variant-numeric:tabular-nums}
.badge{padding:1px 7px;border-radius:9px;font-weight:600;font-size:.9em}
.ok{background:#d4edda;color:#155724}.bad{background:#f8d7da;color:#721c24}
.warn{background:#fff3cd;color:#856404}
.notes{background:#fff8e1;border-left:4px solid #f0ad4e;padding:8px 14px;margin:12px 0}
.fig{min-height:420px}.drawing svg{width:100%;height:auto}
img.static{max-width:100%;border:1px solid #e1e4e8;margin:6px 0}
details summary{cursor:pointer;color:#1d3557;margin:6px 0}
code{background:#eef1f4;padding:0 4px;border-radius:3px}
"""

#: Catches script errors before anything else runs, for the page's own status.
ERRORS = (
    "<script>window.rheolinErrors=[];window.addEventListener('error',function(e){"
    "window.rheolinErrors.push(String(e.message||e));});</script>"
)

#: Draws every figure from its JSON, then records how many were drawn.
LOADER = """<script>
(function(){
  var divs=document.querySelectorAll('div.fig'), jobs=[];
  divs.forEach(function(div){
    try{
      var spec=JSON.parse(document.getElementById(div.id+'-data').textContent);
      jobs.push(Plotly.newPlot(div, spec.data, spec.layout,
        {responsive:true, displaylogo:false, toImageButtonOptions:{format:'svg'}}));
    }catch(e){window.rheolinErrors.push(div.id+': '+e);}
  });
  Promise.all(jobs).catch(function(e){window.rheolinErrors.push(String(e));}).then(function(){
    var drawn=0;
    divs.forEach(function(d){if(d.querySelector('svg.main-svg')){drawn++;}});
    document.body.setAttribute('data-rendered', String(drawn));
    document.body.setAttribute('data-figures', String(divs.length));
    document.body.setAttribute('data-errors', window.rheolinErrors.join(' | '));
    var asked=performance.getEntriesByType('resource').map(function(r){return r.name;});
    document.body.setAttribute('data-requests', asked.filter(function(n){
      return n.indexOf('data:')!==0;}).join(' '));
  });
})();
</script>"""


class Page:
    """Sections of HTML collected in order, then :meth:`html` writes the whole page."""

    def __init__(self, title: str, subtitle: str) -> None:
        self.title = title
        self.subtitle = subtitle
        self.sections: list[tuple[str, str, str]] = []
        self.figures = 0

    def section(self, key: str, heading: str, body: str) -> None:
        """Add a section (``key``: its anchor) unless ``body`` is empty."""
        if body.strip():
            self.sections.append((key, heading, body))

    def figure(self, fig: Any) -> str:
        """A plotly figure as a div and its data (drawn by the page's loader)."""
        self.figures += 1
        name = f"fig{self.figures}"
        data = pio.to_json(fig, validate=False).replace("</", "<\\/")
        return (
            f'<div class="fig" id="{name}"></div>'
            f'<script type="application/json" id="{name}-data">{data}</script>'
        )

    @staticmethod
    def svg(fig: Any) -> str:
        """A matplotlib figure as inline SVG."""
        buf = io.StringIO()
        fig.savefig(buf, format="svg")
        text = buf.getvalue()
        return '<div class="drawing">' + text[text.find("<svg") :] + "</div>"

    @staticmethod
    def png(name: str, data: bytes) -> str:
        """A PNG embedded as a data URI."""
        uri = "data:image/png;base64," + base64.b64encode(data).decode("ascii")
        return f'<img class="static" alt="{html.escape(name)}" src="{uri}">'

    def html(self) -> str:
        """The whole page."""
        nav = "".join(f'<a href="#{k}">{html.escape(h)}</a>' for k, h, _ in self.sections)
        body = "".join(
            f'<section id="{k}"><h2>{html.escape(h)}</h2>{b}</section>' for k, h, b in self.sections
        )
        stamp = datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%d %H:%M UTC")
        return (
            '<!DOCTYPE html><html lang="en"><head><meta charset="utf-8">'
            f"<title>{html.escape(self.title)}</title>"
            '<meta name="viewport" content="width=device-width, initial-scale=1">'
            f"<style>{CSS}</style>{ERRORS}"
            f'<script type="text/javascript">{get_plotlyjs()}</script></head><body>'
            f"<header><h1>{html.escape(self.title)}</h1><p>{html.escape(self.subtitle)}"
            f" · rheolin {html.escape(__version__)} · {stamp}</p></header>"
            f"<nav>{nav}</nav><main>{body}</main>{LOADER}</body></html>"
        )
