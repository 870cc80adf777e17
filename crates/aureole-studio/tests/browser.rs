//! The studio page in a real headless Chromium (Debian's `chromium`, which
//! `.ci/run` installs; without it these tests say so and pass): the page
//! loads and renders with no console error, its own tone mapping matches the
//! server's, every view shows, and an unreadable file or a path outside the
//! roots shows its one line.
//! Screenshots are saved in `target/studio-screenshots/`.

#[path = "../../../tests/support/required.rs"]
mod required;
use std::path::{Path, PathBuf};
use std::process::Command;

mod common;

use common::{server, TOKEN};

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
        required::missing("browser", "no chromium (apt-get install chromium)");
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("broken.exr"), b"v/1\x01 cut short").unwrap();
    let addr = server(dir.path());
    // Opened as `aureole studio` prints it: with the token, which the page
    // keeps in a cookie.
    let base = format!("http://{addr}/?token={TOKEN}&");

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
            .map(|_| visit(&browser, &format!("{base}{query}"), name))
            .find(|page| page.dom.contains("data-display-mismatch"))
            .unwrap_or_else(|| panic!("{name}: the page never finished its self-check"));
        let worst = page.attribute("data-display-mismatch");
        assert!(
            worst <= 1,
            "{name}: the page's picture differs by {worst} codes"
        );
    }

    for view in ["split", "kernel", "glare", "original"] {
        let page = visit(&browser, &format!("{base}view={view}"), view);
        assert!(page.attribute("data-rendered") >= 1, "{view}");
        assert_eq!(
            page.attribute("data-failed"),
            0,
            "{view}: {}",
            page.text_of("error")
        );
    }
    // The command line under the picture is the server's, for this view.
    let glare = visit(
        &browser,
        &format!("{base}view=glare&tonemap=reinhard"),
        "command",
    );
    let command = glare.text_of("command");
    assert!(
        command.contains("aureole apply")
            && command.contains("--config camera.toml")
            && command.contains("--glare-only")
            && command.contains("--tonemap reinhard"),
        "{command}"
    );
    // The split view puts the original under a handle.
    let split = visit(&browser, &format!("{base}view=split"), "split");
    assert!(
        !split.dom.contains(r#"id="handle" hidden"#),
        "the handle is hidden"
    );

    let broken = visit(&browser, &format!("{base}image=broken.exr"), "broken");
    assert!(broken.attribute("data-failed") >= 1);
    assert!(
        broken.text_of("error").contains("broken.exr"),
        "{}",
        broken.text_of("error")
    );

    let outside = visit(&browser, &format!("{base}image=/etc/hostname"), "outside");
    assert!(
        outside.text_of("error").contains("outside the folders"),
        "{}",
        outside.text_of("error")
    );
}

/// Serves `page` as HTML to every request on a port of its own: another
/// site, as far as the browser knows.
fn other_site(page: String) -> std::net::SocketAddr {
    use std::io::{Read, Write};
    let listener = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let addr = listener.local_addr().unwrap();
    std::thread::spawn(move || {
        for mut stream in listener.incoming().flatten() {
            let mut head = [0u8; 4096];
            let _ = stream.read(&mut head);
            let _ = write!(
                stream,
                "HTTP/1.1 200 OK\r\nContent-Type: text/html\r\nContent-Length: {}\r\nConnection: close\r\n\r\n{page}",
                page.len()
            );
        }
    });
    addr
}

/// Chromium with a profile of its own in `profile`, so that a cookie set
/// by one visit is there for the next, as in a user's browser.
fn dump(browser: &Path, profile: &Path, extra: &[&str], url: &str) -> String {
    let output = Command::new(browser)
        .args([
            "--headless=new",
            "--no-sandbox",
            "--disable-gpu",
            "--virtual-time-budget=20000",
        ])
        .arg(format!("--user-data-dir={}", profile.display()))
        .args(extra)
        .args(["--dump-dom", url])
        .output()
        .unwrap();
    String::from_utf8_lossy(&output.stdout).into_owned()
}

#[test]
fn pages_of_other_sites_cannot_drive_the_studio_in_a_real_browser() {
    let Some(browser) = chromium() else {
        required::missing("browser", "no chromium (apt-get install chromium)");
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let profile = tempfile::tempdir().unwrap();
    let addr = server(dir.path());
    let studio = format!("http://{addr}");
    // The user opens the studio: the browser now holds its cookie.
    let opened = dump(
        &browser,
        profile.path(),
        &[],
        &format!("{studio}/?token={TOKEN}"),
    );
    assert!(opened.contains(r#"id="stage""#), "{opened}");

    // Then a page of another site tries everything a page can send: a
    // listing and a render read with the user's cookie, and the simple
    // (text/plain, no-cors) export that needs no reading at all.
    let config = serde_json::to_string(aureole::presets::PRESETS[0].toml).unwrap();
    let page = format!(
        r#"<!doctype html><body><script>
const studio = "{studio}";
const job = JSON.stringify({{ image: "demo", config: {config}, output: "stolen.exr" }});
const tries = {{
  list: () => fetch(studio + "/api/images", {{ credentials: "include" }}).then((r) => r.text()),
  render: () => fetch(studio + "/api/render", {{ method: "POST", credentials: "include",
    headers: {{ "Content-Type": "application/json" }}, body: JSON.stringify({{ image: "demo", config: {config}, width: 64 }}) }})
    .then((r) => r.status),
  export: () => fetch(studio + "/api/export", {{ method: "POST", mode: "no-cors", credentials: "include",
    headers: {{ "Content-Type": "text/plain" }}, body: job }}).then((r) => r.type),
}};
(async () => {{
  const out = {{}};
  for (const [name, attempt] of Object.entries(tries)) {{
    try {{ out[name] = String(await attempt()); }} catch (e) {{ out[name] = "blocked"; }}
  }}
  document.body.dataset.result = JSON.stringify(out);
}})();
</script></body>"#
    );
    let attacker = other_site(page);
    let dom = dump(
        &browser,
        profile.path(),
        &[],
        &format!("http://{attacker}/"),
    );
    assert!(
        dom.contains("data-result"),
        "the other site's page did not finish: {dom}"
    );
    // The listing's JSON names the roots: the other site never sees it.
    assert!(
        !dom.contains("roots"),
        "the other site read the listing: {dom}"
    );
    assert!(
        !dir.path().join("stolen.exr").exists(),
        "the other site exported"
    );
    let status: serde_json::Value = {
        let url = format!("{studio}/api/status?token={TOKEN}");
        let text = dump(&browser, profile.path(), &[], &url);
        let json = &text[text.find('{').unwrap()..=text.rfind('}').unwrap()];
        serde_json::from_str(json).unwrap()
    };
    assert_eq!(status["rendering"], 0);
    // The export may still be running when the file is looked for: the
    // studio's job list says whether it was ever started.
    let job = dump(
        &browser,
        profile.path(),
        &[],
        &format!("{studio}/api/export/1?token={TOKEN}"),
    );
    assert!(job.contains("no export 1"), "{job}");

    // A DNS-rebinding page: another name for the studio's own address,
    // even with the token, is refused.
    let rebound = dump(
        &browser,
        profile.path(),
        &["--host-resolver-rules=MAP evil.test 127.0.0.1"],
        &format!("http://evil.test:{}/api/images?token={TOKEN}", addr.port()),
    );
    assert!(rebound.contains("not this studio"), "{rebound}");
    assert!(!rebound.contains("roots"), "{rebound}");
}

#[test]
fn two_tabs_render_side_by_side_without_cancelling_each_other() {
    let Some(browser) = chromium() else {
        required::missing("browser", "no chromium (apt-get install chromium)");
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let addr = server(dir.path());
    // A spectral aperture: seconds of work, so the two renders overlap.
    let url = format!("http://{addr}/?token={TOKEN}&preset=camera-f8-7blade");
    let tabs: Vec<_> = (0..2)
        .map(|_| {
            let (browser, url) = (browser.clone(), url.clone());
            std::thread::spawn(move || {
                let profile = tempfile::tempdir().unwrap();
                dump(&browser, profile.path(), &["--window-size=1400,860"], &url)
            })
        })
        .collect();
    for tab in tabs {
        let dom = tab.join().unwrap();
        assert!(dom.contains("data-rendered"), "{dom}");
        assert!(!dom.contains("data-failed=\"1\""), "{dom}");
    }
    let mut stream = std::net::TcpStream::connect(addr).unwrap();
    use std::io::{Read, Write};
    write!(
        stream,
        "GET /api/status HTTP/1.1\r\nHost: {addr}\r\nAuthorization: Bearer {TOKEN}\r\nConnection: close\r\n\r\n"
    )
    .unwrap();
    let mut reply = String::new();
    stream.read_to_string(&mut reply).unwrap();
    assert!(reply.contains("\"cancelled\":0"), "{reply}");
}

#[test]
fn a_camera_with_lens_ghosts_renders_and_draws_its_lens() {
    let Some(browser) = chromium() else {
        required::missing("browser", "no chromium (apt-get install chromium)");
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let addr = server(dir.path());
    let page = visit(
        &browser,
        &format!("http://{addr}/?token={TOKEN}&preset=camera-f8-7blade-ghosts"),
        "ghosts",
    );
    assert!(page.attribute("data-rendered") >= 1, "{}", page.dom);
    assert_eq!(
        page.attribute("data-failed"),
        0,
        "{}",
        page.text_of("error")
    );
    // The ghosts' panel: its lens chosen among the shipped ones, and drawn.
    assert!(page.dom.contains(r#"data-param="lens""#), "no lens control");
    assert!(
        page.dom
            .contains(r#"<option value="double-gauss-50mm-f1.4""#),
        "no shipped lens offered"
    );
    assert_eq!(page.attribute("data-drawn"), 1, "the lens is not drawn");
}
