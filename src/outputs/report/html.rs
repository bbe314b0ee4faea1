//! The HTML around the report's content: escaping, tables, figures, the
//! page with its inline style (no script, no fetch: the file opens from an
//! e-mail attachment or a USB stick and prints as it shows).

use std::fmt::Write;

/// Text made safe inside HTML elements and attribute values.
pub fn escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            c => out.push(c),
        }
    }
    out
}

/// A number with `digits` significant digits; "—" for none.
pub fn number(v: Option<f64>, digits: usize) -> String {
    match v {
        Some(v) if v.is_finite() => {
            let magnitude = if v == 0.0 { 0 } else { v.abs().log10().floor() as i32 };
            if !(-3..6).contains(&magnitude) {
                format!("{v:.*e}", digits.saturating_sub(1))
            } else {
                let decimals = (digits as i32 - 1 - magnitude).max(0) as usize;
                format!("{v:.decimals$}")
            }
        }
        _ => "—".into(),
    }
}

/// A table: a caption, header cells and rows of cells (already HTML), in a
/// container that scrolls sideways on its own if it must, never the page.
pub fn table(id: &str, caption: &str, header: &[&str], rows: &[Vec<String>]) -> String {
    let mut s = format!(
        "<div class=\"table\"><table id=\"{}\"><caption>{}</caption><thead><tr>",
        escape(id),
        escape(caption)
    );
    for h in header {
        let _ = write!(s, "<th scope=\"col\">{}</th>", escape(h));
    }
    s.push_str("</tr></thead><tbody>");
    for row in rows {
        s.push_str("<tr>");
        for cell in row {
            let _ = write!(s, "<td>{cell}</td>");
        }
        s.push_str("</tr>");
    }
    s.push_str("</tbody></table></div>");
    s
}

/// A figure: its inline SVG and a caption saying how to read it.
pub fn figure(id: &str, svg: &str, caption: &str) -> String {
    format!(
        "<figure id=\"{}\" class=\"figure\">{svg}<figcaption>{}</figcaption></figure>",
        escape(id),
        escape(caption)
    )
}

/// A section with a heading.
pub fn section(id: &str, heading: &str, body: &str) -> String {
    format!(
        "<section id=\"{}\"><h2>{}</h2>{body}</section>",
        escape(id),
        escape(heading)
    )
}

const STYLE: &str = "\
:root{color-scheme:light;font-family:system-ui,-apple-system,'Segoe UI',Roboto,sans-serif;line-height:1.45;color:#1a1a1a}\
*{box-sizing:border-box}\
body{margin:0 auto;padding:1rem;max-width:60rem}\
h1{font-size:1.45rem;margin:.2rem 0}h2{font-size:1.15rem;margin:1.6rem 0 .5rem;border-bottom:1px solid #ccc}\
h1,h2,p,li,td,th{overflow-wrap:break-word}code{overflow-wrap:anywhere;word-break:break-all}\
.subtitle{color:#555;margin:0 0 1rem}\
#verdict{border:2px solid #888;border-radius:.5rem;padding:.8rem 1rem;margin:1rem 0}\
#verdict.high{border-color:#c81e1e;background:#fdecec}#verdict.medium{border-color:#c77800;background:#fff5e0}\
#verdict.low{border-color:#2e7d32;background:#edf7ee}#verdict.unjudged{border-color:#777;background:#f3f3f3}\
#verdict p{margin:.3rem 0;font-size:1.1rem}\
.priority{display:inline-block;font-weight:700;padding:.1rem .5rem;border-radius:.3rem;color:#fff;background:#777}\
.high .priority{background:#c81e1e}.medium .priority{background:#c77800}.low .priority{background:#2e7d32}\
.badge{display:inline-block;white-space:nowrap;font-weight:700;padding:0 .4rem;border-radius:.3rem;color:#fff;background:#777}\
.badge.high{background:#c81e1e}.badge.medium{background:#c77800}.badge.low{background:#2e7d32}\
.figures{display:grid;grid-template-columns:repeat(auto-fit,minmax(min(100%,24rem),1fr));gap:1rem}\
figure{margin:0;min-width:0}figure svg{display:block;width:100%;height:auto}\
figcaption{font-size:.85rem;color:#444}\
.table{overflow-x:auto;max-width:100%}\
table{border-collapse:collapse;font-size:.9rem;margin:.5rem 0}\
caption{text-align:left;font-size:.85rem;color:#444;caption-side:bottom;padding-top:.3rem}\
th,td{border-bottom:1px solid #ddd;padding:.25rem .5rem;text-align:left;vertical-align:top}\
td.out,span.out{color:#c81e1e;font-weight:700}\
details pre{white-space:pre-wrap;overflow-wrap:anywhere;font-size:.8rem;background:#f6f6f6;padding:.5rem}\
footer{margin-top:2rem;font-size:.8rem;color:#555}\
@media print{body{max-width:none}section{break-inside:avoid-page}figure{break-inside:avoid}}\
";

/// The whole page: title, body content; nothing fetched from anywhere.
pub fn page(title: &str, body: &str) -> String {
    refreshing_page(title, body, None)
}

/// A page the browser loads again every `refresh` seconds.
pub fn refreshing_page(title: &str, body: &str, refresh: Option<u32>) -> String {
    let refresh = refresh.map_or(String::new(), |s| {
        format!("<meta http-equiv=\"refresh\" content=\"{s}\">")
    });
    format!(
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">{refresh}\
<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\"><link rel=\"icon\" href=\"data:,\">\
<meta http-equiv=\"Content-Security-Policy\" content=\"default-src 'none'; style-src 'unsafe-inline'; img-src data:\">\
<title>{}</title><style>{STYLE}</style></head><body>{body}</body></html>\n",
        escape(title)
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn text_is_escaped_and_numbers_read() {
        assert_eq!(escape("<a href=\"x\">&'"), "&lt;a href=&quot;x&quot;&gt;&amp;&#39;");
        assert_eq!(number(Some(3.4915), 3), "3.49");
        assert_eq!(number(Some(84315296.8), 3), "8.43e7");
        assert_eq!(number(Some(0.0817), 2), "0.082");
        assert_eq!(number(None, 3), "—");
        assert_eq!(number(Some(f64::NAN), 3), "—");
    }
}
