//! The diagnosis's outputs: `report.json`, the two model files, and an HTML
//! report with its chart, all written atomically; nothing is written when
//! the diagnosis fails.

use std::path::Path;

use crate::diagnose::Diagnosis;
use crate::error::Result;
use crate::io::{create_dir, write_atomically};

fn escape(text: &str) -> String {
    text.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;")
}

/// Writes `report.json`, `baseline-model.toml`, `fitted-model.toml`,
/// `report.html` and `gap.png`/`gap.svg` into `out`.
pub fn write_diagnosis(out: &Path, diagnosis: &Diagnosis, source: &Path, elapsed_s: f64) -> Result<()> {
    create_dir(out)?;
    let mut report = diagnosis.report_json();
    report["source"] = serde_json::json!(source.display().to_string());
    report["elapsed_s"] = serde_json::json!(elapsed_s);
    write_atomically(&out.join("report.json"), |w| {
        serde_json::to_writer_pretty(&mut *w, &report)?;
        writeln!(w)
    })?;
    let header = |what: &str| format!("# {what} written by stickslip diagnose from {}\n# Run it with: stickslip sweep --config THIS_FILE\n\n", source.display());
    write_atomically(&out.join("baseline-model.toml"), |w| {
        w.write_all(header("The calibrated baseline").as_bytes())?;
        w.write_all(diagnosis.baseline.to_toml_string().as_bytes())
    })?;
    write_atomically(&out.join("fitted-model.toml"), |w| {
        w.write_all(header(&format!("The baseline plus the verdict's effect ({})", diagnosis.verdict)).as_bytes())?;
        w.write_all(diagnosis.fitted.to_toml_string().as_bytes())
    })?;
    crate::plot::write_gap_chart(out, diagnosis)?;
    let html = html(diagnosis, &report);
    write_atomically(&out.join("report.html"), |w| w.write_all(html.as_bytes()))
}

fn html(d: &Diagnosis, report: &serde_json::Value) -> String {
    let gap = &report["gap"];
    let num = |v: &serde_json::Value| v.as_f64().map_or("–".to_string(), |x| format!("{x:.3}"));
    let mut s = String::new();
    s.push_str("<!doctype html><html><head><meta charset=\"utf-8\"><title>stickslip diagnosis</title><style>");
    s.push_str("body{font-family:sans-serif;max-width:960px;margin:2em auto;color:#222}table{border-collapse:collapse;margin:1em 0}td,th{border:1px solid #ccc;padding:4px 8px;text-align:right}th{background:#f3f3f3}td:first-child,th:first-child{text-align:left}.verdict{font-size:1.4em}");
    s.push_str("</style></head><body><h1>Diagnosis of the sim-to-real gap</h1>");
    s.push_str(&format!(
        "<p class=\"verdict\">Verdict: <b>{}</b> (confidence {:.2})</p>",
        escape(&d.verdict),
        d.confidence
    ));
    s.push_str(&format!(
        "<p>Gap metric: {}.</p><table><tr><th></th><th>baseline</th><th>after</th><th>shrink</th></tr><tr><td>fitting units</td><td>{}</td><td>{}</td><td>{}</td></tr><tr><td>held-out units</td><td>{}</td><td>{}</td><td>{}</td></tr></table>",
        escape(gap["metric"].as_str().unwrap_or("")),
        num(&gap["baseline"]),
        num(&gap["after"]),
        num(&gap["shrink"]),
        num(&gap["heldout_baseline"]),
        num(&gap["heldout_after"]),
        num(&gap["heldout_shrink"]),
    ));
    s.push_str("<h2>Where the baseline departs from the data</h2><img src=\"gap.png\" alt=\"|z| per observable, baseline and fitted\" style=\"max-width:100%\">");
    s.push_str("<table><tr><th>condition</th><th>observable</th><th>|z|</th><th>detail</th></tr>");
    for loc in report["locations"].as_array().into_iter().flatten().take(30) {
        s.push_str(&format!(
            "<tr><td>{} Hz, {:.3} N</td><td>{}</td><td>{:.1}</td><td style=\"text-align:left\">{}</td></tr>",
            loc["excitation_frequency_hz"],
            loc["normal_force_n"].as_f64().unwrap_or(0.0),
            escape(loc["observable"].as_str().unwrap_or("")),
            loc["score"].as_f64().unwrap_or(0.0),
            escape(loc["detail"].as_str().unwrap_or(""))
        ));
    }
    s.push_str("</table><h2>Candidates (each refitted with the baseline's friction level)</h2><table><tr><th>effect</th><th>gap (fit)</th><th>gap (held-out)</th><th>shrink</th><th>held-out shrink</th><th>parameters</th></tr>");
    for c in &d.candidates {
        s.push_str(&format!(
            "<tr><td>{}</td><td>{:.3}</td><td>{:.3}</td><td>{:.3}</td><td>{}</td><td style=\"text-align:left\">{}</td></tr>",
            escape(&c.effect),
            c.gap_fit,
            c.gap_heldout,
            c.shrink,
            c.heldout_shrink.map_or("–".into(), |h| format!("{h:.3}")),
            escape(&c.parameters.iter().map(|(k, v)| format!("{k} = {v:.4e}")).collect::<Vec<_>>().join(", "))
        ));
    }
    s.push_str(&format!(
        "</table><p>A candidate counts only if it lowers the held-out gap by more than {:.3} (noise threshold). Models: <a href=\"baseline-model.toml\">baseline-model.toml</a>, <a href=\"fitted-model.toml\">fitted-model.toml</a>; both run with <code>stickslip sweep --config</code>.</p></body></html>\n",
        d.noise_threshold
    ));
    s
}
