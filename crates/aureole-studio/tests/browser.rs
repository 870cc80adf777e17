//! The studio page in a real headless Chromium (Debian's `chromium`, which
//! `.ci/run` installs; without it these tests say so and pass): the page
//! loads and renders with no console error, its own tone mapping matches the
//! server's, every view shows, and an unreadable file or a path outside the
//! roots shows its one line.
//! Screenshots are saved in `target/studio-screenshots/`.

use std::path::{Path, PathBuf};
use std::process::Command;

mod common;

use common::server;

fn chromium() -> Option<PathBuf> {
    ["chromium", "chromium-browser", "google-chrome"]
        .iter()
        .map(PathBuf::from)
        .find(|p| {
            Command::new(p)
                .arg("--version")
                .output()
                .is_ok_and(|o| o.status.success())
        })
}

/// What the page shows after its scripts ran: its DOM, what the console
/// said, and a screenshot saved as `name`.
struct Visit {
    dom: String,
    console: Vec<String>,
}

fn visit(browser: &Path, url: &str, name: &str) -> Visit {
    let common = [
        "--headless=new",
        "--no-sandbox",
        "--disable-gpu",
        // WebGL2 on the CPU (SwiftShader), as on a machine without a GPU.
        "--enable-unsafe-swiftshader",
        "--hide-scrollbars",
        "--window-size=1400,860",
        "--virtual-time-budget=30000",
    ];
    let dumped = Command::new(browser)
        .args(common)
        .args(["--enable-logging=stderr", "--v=0", "--dump-dom", url])
        .output()
        .unwrap();
    let console = String::from_utf8_lossy(&dumped.stderr)
        .lines()
        .filter(|l| l.contains("CONSOLE"))
        .map(str::to_string)
        .collect();
    let shots = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../target/studio-screenshots");
    std::fs::create_dir_all(&shots).unwrap();
    let shot = shots.join(format!("{name}.png"));
    Command::new(browser)
        .args(common)
        .arg(format!("--screenshot={}", shot.display()))
        .arg(url)
        .output()
        .unwrap();
    assert!(shot.is_file(), "no screenshot {}", shot.display());
    Visit {
        dom: String::from_utf8_lossy(&dumped.stdout).into_owned(),
        console,
    }
}

impl Visit {
    fn attribute(&self, name: &str) -> usize {
        let key = format!("{name}=\"");
        self.dom
            .find(&key)
            .and_then(|at| {
                let rest = &self.dom[at + key.len()..];
                rest[..rest.find('"')?].parse().ok()
            })
            .unwrap_or(0)
    }

    fn text_of(&self, id: &str) -> String {
        let key = format!("id=\"{id}\"");
        let Some(at) = self.dom.find(&key) else {
            return String::new();
        };
        let rest = &self.dom[at..];
        let start = rest.find('>').map_or(0, |i| i + 1);
        let end = rest[start..].find('<').map_or(start, |i| start + i);
        rest[start..end].to_string()
    }
}

#[test]
fn the_page_renders_in_a_real_browser_and_shows_every_view_and_error() {
    let Some(browser) = chromium() else {
        eprintln!("skipped: no chromium (apt-get install chromium)");
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("broken.exr"), b"v/1\x01 cut short").unwrap();
    let addr = server(dir.path());
    let base = format!("http://{addr}/");

    let first = visit(&browser, &base, "result");
    assert!(first.attribute("data-rendered") >= 1, "{}", first.dom);
    assert_eq!(
        first.attribute("data-failed"),
        0,
        "{}",
        first.text_of("error")
    );
    assert!(
        first.text_of("numbers").contains("energy in"),
        "{}",
        first.text_of("numbers")
    );
    // The camera's panels, from the library's schema.
    for parameter in ["sensor_width_mm", "blades", "roundness", "wavelength_nm"] {
        assert!(
            first.dom.contains(&format!(r#"data-param="{parameter}""#)),
            "no control for {parameter}"
        );
    }
    let errors: Vec<&String> = first
        .console
        .iter()
        .filter(|l| l.contains("ERROR") || l.contains("Uncaught"))
        .collect();
    assert!(errors.is_empty(), "console: {errors:?}");
    assert!(
        first.dom.contains(r#"data-display="webgl2""#),
        "the page does not tone-map in WebGL2"
    );

    // The page tone-maps the linear preview itself, in WebGL2 or on a 2D
    // canvas; what it draws is what the server's display path (aureole-io)
    // draws, within a code, for every curve.
    for (query, name) in [
        ("selfcheck=1", "selfcheck"),
        ("selfcheck=1&view=glare", "selfcheck-glare"),
        ("selfcheck=1&tonemap=reinhard&ev=3", "selfcheck-reinhard"),
        ("selfcheck=1&tonemap=clip&ev=1", "selfcheck-clip"),
        ("selfcheck=1&display=2d", "selfcheck-canvas"),
        (
            "selfcheck=1&display=2d&tonemap=reinhard&ev=3",
            "selfcheck-canvas-reinhard",
        ),
    ] {
        // The dump may come before the page's second fetch is decoded: a
        // few tries.
        let page = (0..4)
            .map(|_| visit(&browser, &format!("{base}?{query}"), name))
            .find(|page| page.dom.contains("data-display-mismatch"))
            .unwrap_or_else(|| panic!("{name}: the page never finished its self-check"));
        let worst = page.attribute("data-display-mismatch");
        assert!(
            worst <= 1,
            "{name}: the page's picture differs by {worst} codes"
        );
    }

    for view in ["split", "kernel", "glare", "original"] {
        let page = visit(&browser, &format!("{base}?view={view}"), view);
        assert!(page.attribute("data-rendered") >= 1, "{view}");
        assert_eq!(
            page.attribute("data-failed"),
            0,
            "{view}: {}",
            page.text_of("error")
        );
    }
    // The split view puts the original under a handle.
    let split = visit(&browser, &format!("{base}?view=split"), "split");
    assert!(
        !split.dom.contains(r#"id="handle" hidden"#),
        "the handle is hidden"
    );

    let broken = visit(&browser, &format!("{base}?image=broken.exr"), "broken");
    assert!(broken.attribute("data-failed") >= 1);
    assert!(
        broken.text_of("error").contains("broken.exr"),
        "{}",
        broken.text_of("error")
    );

    let outside = visit(&browser, &format!("{base}?image=/etc/hostname"), "outside");
    assert!(
        outside.text_of("error").contains("outside the folders"),
        "{}",
        outside.text_of("error")
    );
}
