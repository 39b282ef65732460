//! A small static-HTML writer: a page with tables, figures and links, no scripts, no server, every link relative.

/// Escapes text for HTML (the SVG writer's escaping: `&apos;` is an HTML5 entity too).
pub use crate::render::chart::escape_xml as escape;

const CSS: &str = "\
body{font-family:system-ui,-apple-system,'Segoe UI',Roboto,Helvetica,Arial,sans-serif;margin:0;color:#222;background:#f6f6f4}
header{background:#2b3a42;color:#fff;padding:18px 28px}
header h1{margin:0 0 4px 0;font-size:24px}
header p{margin:0;color:#cfd8dc;font-size:14px}
main{padding:8px 28px 40px 28px;max-width:1800px}
h2{font-size:19px;border-bottom:2px solid #2b3a42;padding-bottom:4px;margin-top:28px}
table{border-collapse:collapse;background:#fff;font-size:14px;margin:6px 0 12px 0}
th,td{border:1px solid #d4d4d4;padding:4px 9px;text-align:right;white-space:nowrap}
th{background:#eceff1}
td.l,th.l{text-align:left;white-space:normal}
tr.best td{background:#fff5e6;font-weight:600}
.row{display:flex;flex-wrap:wrap;gap:24px;align-items:flex-start}
.grid{display:grid;grid-template-columns:repeat(auto-fill,minmax(520px,1fr));gap:18px}
.pair{display:grid;grid-template-columns:repeat(auto-fit,minmax(520px,1fr));gap:18px}
figure{margin:0;background:#fff;border:1px solid #ddd;padding:8px}
figure img{width:100%;height:auto;display:block}
figcaption{font-size:13px;color:#444;padding-top:6px}
.note{font-size:13px;color:#555;max-width:1100px}
.big{font-size:17px}
pre{background:#fff;border:1px solid #ddd;padding:10px;font-size:12px;overflow:auto;max-height:520px}
a{color:#0b5fa5}
ul.files{columns:3;font-size:14px}
";

/// An HTML page being built.
#[derive(Debug, Clone, Default)]
pub struct Page {
    body: String,
    title: String,
}

impl Page {
    /// A page with a title and a header line under it (both plain text).
    pub fn new(title: &str, subtitle: &str) -> Self {
        let body = format!("<header><h1>{}</h1><p>{}</p></header>\n<main>\n", escape(title), escape(subtitle));
        Page { body, title: title.to_string() }
    }

    /// Appends raw HTML.
    pub fn raw(&mut self, html: &str) {
        self.body.push_str(html);
        self.body.push('\n');
    }

    /// A section heading.
    pub fn h2(&mut self, text: &str) {
        self.raw(&format!("<h2>{}</h2>", escape(text)));
    }

    /// A paragraph of plain text with class `note`.
    pub fn note(&mut self, text: &str) {
        self.raw(&format!("<p class=\"note\">{}</p>", escape(text)));
    }

    /// The finished document.
    pub fn finish(mut self) -> String {
        self.body.push_str("</main>\n");
        format!(
            "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n<title>{}</title>\n<style>\n{CSS}</style>\n</head>\n<body>\n{}</body>\n</html>\n",
            escape(&self.title),
            self.body
        )
    }
}

/// A table: `head` cells (plain text), rows of cells (raw HTML); columns listed in `left` are left-aligned (text),
/// the others right-aligned (numbers); rows whose index is in `highlight` get the class `best`.
pub fn table(head: &[&str], rows: &[Vec<String>], left: &[usize], highlight: &[usize]) -> String {
    let mut s = String::from("<table><thead><tr>");
    for (i, h) in head.iter().enumerate() {
        let class = if left.contains(&i) { " class=\"l\"" } else { "" };
        s.push_str(&format!("<th{class}>{}</th>", escape(h)));
    }
    s.push_str("</tr></thead><tbody>");
    for (r, row) in rows.iter().enumerate() {
        let class = if highlight.contains(&r) { " class=\"best\"" } else { "" };
        s.push_str(&format!("<tr{class}>"));
        for (i, c) in row.iter().enumerate() {
            let class = if left.contains(&i) { " class=\"l\"" } else { "" };
            s.push_str(&format!("<td{class}>{c}</td>"));
        }
        s.push_str("</tr>");
    }
    s.push_str("</tbody></table>");
    s
}

/// A figure: the image `src` (linked to itself), a bold caption title, text, and links (label, href).
pub fn figure(src: &str, title: &str, text: &str, links: &[(&str, String)]) -> String {
    let links: Vec<String> =
        links.iter().map(|(l, h)| format!("<a href=\"{}\">{}</a>", escape(h), escape(l))).collect();
    format!(
        "<figure><a href=\"{src}\"><img src=\"{src}\" alt=\"{alt}\" loading=\"lazy\"></a><figcaption><b>{t}</b> {text} {links}</figcaption></figure>",
        src = escape(src),
        alt = escape(title),
        t = escape(title),
        text = escape(text),
        links = links.join(" · ")
    )
}

/// A number for tables: up to 3 significant decimals, `–` for NaN.
pub fn num(v: f64) -> String {
    if !v.is_finite() {
        return "–".into();
    }
    let a = v.abs();
    if a >= 1000.0 {
        format!("{v:.0}")
    } else if a >= 100.0 {
        format!("{v:.1}")
    } else if a >= 1.0 {
        format!("{v:.2}")
    } else if a == 0.0 {
        "0".into()
    } else {
        format!("{v:.3}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn escapes_and_builds() {
        assert_eq!(escape("<a & \"b\">"), "&lt;a &amp; &quot;b&quot;&gt;");
        let mut p = Page::new("T <1>", "sub");
        p.raw(&table(&["a", "b"], &[vec!["x".into(), "1".into()]], &[0], &[0]));
        let html = p.finish();
        assert!(html.starts_with("<!DOCTYPE html>") && html.contains("T &lt;1&gt;") && html.contains("class=\"best\""));
        assert_eq!(
            (num(1234.4), num(12.346), num(0.01234), num(f64::NAN)),
            ("1234".into(), "12.35".into(), "0.012".into(), "–".into())
        );
    }
}
