//! The HTTP API fuzzed: random and malformed methods, paths, queries,
//! headers and bodies (random bytes, random JSON, and JSON shaped like the
//! API's requests with wrong, hostile and extreme values) sent to every
//! endpoint of a real server. Every request gets an answer, 2xx, 303 (the
//! page's token redirect), 4xx or 503, never a 5xx or a dropped connection
//! (a handler that panicked); the process's peak memory stays within the
//! studio's budget and what a test needs; and the server still serves.
//!
//! `AUREOLE_FUZZ_CASES` sets how many requests (default 300: about half a
//! minute here); CI runs the default.

use std::io::{Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::time::Duration;

use proptest::prelude::*;
use proptest::test_runner::{Config, TestRunner};
use serde_json::Value;

mod common;

use common::{server_within, street, TOKEN};

/// The studio's budget for renders and exports in this test.
const BUDGET: u64 = 512 << 20;

/// The most the test process may hold: the budget, and the test's own
/// memory and the server's code beside it.
const LIMIT: u64 = BUDGET + (256 << 20);

const KEYS: &[&str] = &[
    "image",
    "config",
    "width",
    "view",
    "exposure",
    "white",
    "tonemap",
    "threshold",
    "knee",
    "format",
    "max_kernel",
    "client",
    "output",
    "overwrite",
];

const PATHS: &[&str] = &[
    "/",
    "/app.js",
    "/app.css",
    "/api/presets",
    "/api/images",
    "/api/schema",
    "/api/status",
    "/api/config/read",
    "/api/config/write",
    "/api/render",
    "/api/export",
    "/api/export/1",
];

struct Request {
    method: String,
    path: String,
    headers: Vec<(String, String)>,
    body: Vec<u8>,
}

impl std::fmt::Debug for Request {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} {} {:?} {}",
            self.method,
            self.path,
            self.headers,
            String::from_utf8_lossy(&self.body)
                .chars()
                .take(400)
                .collect::<String>()
        )
    }
}

/// Values of every kind, the API's own among them.
fn value(image: String) -> impl Strategy<Value = Value> {
    let preset = aureole::presets::find("paper-fig5-both").unwrap().toml;
    let leaf = prop_oneof![
        Just(Value::Null),
        any::<bool>().prop_map(Value::Bool),
        prop_oneof![
            Just(0.0),
            Just(-1.0),
            Just(1e308),
            Just(-1e308),
            Just(5e-324),
            Just(64.0),
            Just(4096.0),
            Just(1e9),
            Just(9_007_199_254_740_993.0),
            any::<f64>(),
        ]
        .prop_map(|v| serde_json::Number::from_f64(v).map_or(Value::Null, Value::Number)),
        any::<i64>().prop_map(Value::from),
        any::<u64>().prop_map(Value::from),
        prop_oneof![
            Just(image.clone()),
            Just(format!("{image}/../../../etc/passwd")),
            Just("/etc/passwd".to_string()),
            Just("../out.exr".to_string()),
            Just("out.exr".to_string()),
            Just("out.png".to_string()),
            Just("demo".to_string()),
            Just(preset.to_string()),
            Just("[[effect]]\ntype = \"aperture\"\nblades = 100000\n".to_string()),
            Just("[[effect]]\ntype = \"bloom\"\nradius = \"1e300px\"\n".to_string()),
            Just("64x36".to_string()),
            Just("0x0".to_string()),
            Just("99999x99999".to_string()),
            Just("linear".to_string()),
            Just("glare".to_string()),
            Just("auto".to_string()),
            "\\PC{0,40}",
            ".{0,300}",
        ]
        .prop_map(Value::String),
    ];
    leaf.prop_recursive(3, 24, 6, |inner| {
        prop_oneof![
            prop::collection::vec(inner.clone(), 0..6).prop_map(Value::Array),
            prop::collection::vec(("\\PC{0,12}", inner), 0..6)
                .prop_map(|pairs| Value::Object(pairs.into_iter().collect())),
        ]
    })
}

/// A render (or, with `output`, an export) that would succeed, with a few
/// of its fields then given any value: what reaches the camera.
fn almost_valid(image: String, export: bool) -> impl Strategy<Value = Value> {
    let presets: Vec<&'static str> = aureole::presets::PRESETS.iter().map(|p| p.toml).collect();
    let base = (
        prop::sample::select(presets),
        1usize..160,
        prop::sample::select(vec!["result", "original", "glare", "kernel", "spread"]),
        prop::sample::select(vec!["png", "linear", "rgb8"]),
        "[a-z]{1,8}",
        prop::sample::select(vec!["exr", "png", "pfm", "hdr", "tif", "jpg", "txt"]),
        any::<bool>(),
    );
    let changes = prop::collection::vec((prop::sample::select(KEYS), value(image.clone())), 0..3);
    (base, changes).prop_map(
        move |((config, width, view, format, name, ext, overwrite), changes)| {
            let mut object = serde_json::json!({
                "image": image.clone(),
                "config": config,
                "width": width,
                "view": view,
                "format": format,
            });
            if export {
                object["output"] = Value::from(format!("renders/{name}.{ext}"));
                object["overwrite"] = Value::from(overwrite);
            }
            for (key, v) in changes {
                object[key] = v;
            }
            object
        },
    )
}

/// A JSON object with some of the API's keys, each with any value.
fn shaped(image: String) -> impl Strategy<Value = Value> {
    prop::collection::vec((prop::sample::select(KEYS), value(image)), 0..10).prop_map(|pairs| {
        Value::Object(pairs.into_iter().map(|(k, v)| (k.to_string(), v)).collect())
    })
}

fn body(image: String) -> impl Strategy<Value = Vec<u8>> {
    prop_oneof![
        Just(Vec::new()),
        prop::collection::vec(any::<u8>(), 0..600),
        value(image.clone()).prop_map(|v| v.to_string().into_bytes()),
        shaped(image.clone()).prop_map(|v| v.to_string().into_bytes()),
        // Valid JSON cut short, or with a byte changed.
        (shaped(image), any::<prop::sample::Index>(), any::<u8>()).prop_map(|(v, at, b)| {
            let mut bytes = v.to_string().into_bytes();
            let i = at.index(bytes.len().max(1));
            if i < bytes.len() {
                if b % 2 == 0 {
                    bytes.truncate(i);
                } else {
                    bytes[i] = b;
                }
            }
            bytes
        }),
    ]
}

/// Printable, space-free text: what a request line or a header can carry.
fn token_text(max: usize) -> impl Strategy<Value = String> {
    prop::collection::vec(0x21u8..0x7f, 0..max)
        .prop_map(|b| String::from_utf8(b).unwrap_or_default())
}

/// A request the gate lets through (the right host, token, origin, content
/// type and method), so that the handlers meet what follows: any body,
/// mostly JSON shaped like theirs.
fn admitted(addr: SocketAddr, image: String) -> impl Strategy<Value = Request> {
    let endpoint = prop_oneof![
        1 => prop::sample::select(vec!["/", "/app.js", "/api/presets", "/api/images", "/api/schema", "/api/status"])
            .prop_map(|p| ("GET", p.to_string())),
        1 => (0u32..40).prop_map(|id| ("GET", format!("/api/export/{id}"))),
        1 => (0u32..40).prop_map(|id| ("DELETE", format!("/api/export/{id}"))),
        2 => Just(("POST", "/api/config/read".to_string())),
        2 => Just(("POST", "/api/config/write".to_string())),
        6 => Just(("POST", "/api/render".to_string())),
        4 => Just(("POST", "/api/export".to_string())),
    ];
    let bodies = move |path: &str| {
        let export = path == "/api/export";
        let near = if path == "/api/render" || export {
            4
        } else {
            0
        };
        prop_oneof![
            near => almost_valid(image.clone(), export).prop_map(|v| v.to_string().into_bytes()),
            2 => shaped(image.clone()).prop_map(|v| v.to_string().into_bytes()),
            1 => body(image.clone()),
        ]
    };
    let endpoint =
        endpoint.prop_flat_map(move |(method, path)| (Just((method, path.clone())), bodies(&path)));
    endpoint.prop_map(move |((method, path), body)| Request {
        method: method.to_string(),
        path,
        headers: vec![
            ("Host".to_string(), addr.to_string()),
            ("Authorization".to_string(), format!("Bearer {TOKEN}")),
            ("Origin".to_string(), format!("http://{addr}")),
            ("Content-Type".to_string(), "application/json".to_string()),
        ],
        body,
    })
}

fn request(addr: SocketAddr, image: String) -> impl Strategy<Value = Request> {
    prop_oneof![
        3 => admitted(addr, image.clone()),
        1 => anything(addr, image),
    ]
}

/// Any request: every part of it random or hostile.
fn anything(addr: SocketAddr, image: String) -> impl Strategy<Value = Request> {
    let method = prop::sample::select(vec![
        "GET", "POST", "DELETE", "PUT", "PATCH", "OPTIONS", "HEAD",
    ]);
    let path = prop_oneof![
        4 => prop::sample::select(PATHS).prop_map(str::to_string),
        1 => token_text(20).prop_map(|id| format!("/api/export/{id}")),
        1 => (prop::sample::select(PATHS), token_text(60)).prop_map(|(p, q)| format!("{p}?{q}")),
        1 => prop::sample::select(PATHS).prop_map(|p| format!("{p}?token={TOKEN}&image=../../etc/passwd")),
        1 => token_text(80).prop_map(|p| format!("/{p}")),
        1 => Just(format!("/api/{}", "a/".repeat(1500))),
    ];
    let host = prop_oneof![
        4 => Just(Some(addr.to_string())),
        1 => Just(Some(format!("localhost:{}", addr.port()))),
        1 => Just(Some("evil.example:80".to_string())),
        1 => Just(Some("127.0.0.1".to_string())),
        1 => Just(None),
        1 => token_text(30).prop_map(Some),
    ];
    let auth = prop_oneof![
        4 => Just(Some(("Authorization".to_string(), format!("Bearer {TOKEN}")))),
        1 => Just(Some(("Cookie".to_string(), format!("aureole-studio-{}={TOKEN}", addr.port())))),
        1 => Just(Some(("Authorization".to_string(), "Bearer wrong".to_string()))),
        1 => Just(None),
    ];
    let origin = prop_oneof![
        4 => Just(None),
        1 => Just(Some(format!("http://{addr}"))),
        1 => Just(Some("http://evil.example".to_string())),
        1 => Just(Some("null".to_string())),
    ];
    let content_type = prop_oneof![
        4 => Just(Some("application/json".to_string())),
        1 => Just(Some("application/json; charset=utf-8".to_string())),
        1 => Just(Some("text/plain".to_string())),
        1 => Just(Some("multipart/form-data; boundary=x".to_string())),
        1 => Just(None),
    ];
    let extra = prop::collection::vec(
        (
            "[A-Za-z][A-Za-z-]{0,20}",
            prop::collection::vec(0x20u8..0x7f, 0..80)
                .prop_map(|b| String::from_utf8(b).unwrap_or_default()),
        ),
        0..3,
    );
    (
        method,
        path,
        host,
        auth,
        origin,
        content_type,
        extra,
        body(image),
    )
        .prop_map(
            |(method, path, host, auth, origin, content_type, extra, body)| {
                let mut headers = Vec::new();
                headers.extend(host.map(|h| ("Host".to_string(), h)));
                headers.extend(auth);
                headers.extend(origin.map(|o| ("Origin".to_string(), o)));
                headers.extend(content_type.map(|c| ("Content-Type".to_string(), c)));
                // Framing headers are ours to set.
                headers.extend(extra.into_iter().filter(|(n, _)| {
                    ![
                        "content-length",
                        "transfer-encoding",
                        "connection",
                        "host",
                        "expect",
                    ]
                    .contains(&n.to_ascii_lowercase().as_str())
                }));
                Request {
                    method: method.to_string(),
                    path,
                    headers,
                    body,
                }
            },
        )
}

/// Sends `request` and returns the status of the answer and the start of
/// its body; `None` when the connection ended without one.
fn send(addr: SocketAddr, request: &Request) -> Option<(u16, String)> {
    let mut stream = TcpStream::connect(addr).ok()?;
    stream
        .set_read_timeout(Some(Duration::from_secs(120)))
        .ok()?;
    let mut head = format!("{} {} HTTP/1.1\r\n", request.method, request.path);
    for (name, value) in &request.headers {
        head += &format!("{name}: {value}\r\n");
    }
    head += &format!(
        "Content-Length: {}\r\nConnection: close\r\n\r\n",
        request.body.len()
    );
    stream.write_all(head.as_bytes()).ok()?;
    // A server that answered before the body (a refused request) may have
    // closed its end: the answer is still there to read.
    let _ = stream.write_all(&request.body);
    let mut reply = Vec::new();
    let _ = stream.read_to_end(&mut reply);
    let line = reply.split(|&b| b == b'\n').next()?;
    let status = std::str::from_utf8(line)
        .ok()?
        .split(' ')
        .nth(1)?
        .parse()
        .ok()?;
    let body = reply
        .windows(4)
        .position(|w| w == b"\r\n\r\n")
        .map(|at| {
            String::from_utf8_lossy(&reply[at + 4..])
                .chars()
                .take(200)
                .collect()
        })
        .unwrap_or_default();
    Some((status, body))
}

/// The most resident memory this process has had, in bytes.
fn peak_memory() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

#[test]
fn random_and_malformed_requests_get_answers_and_the_server_keeps_serving() {
    let dir = tempfile::tempdir().unwrap();
    let image = street(dir.path(), "street.exr", (64, 36));
    std::fs::create_dir(dir.path().join("renders")).unwrap();
    let addr = server_within(dir.path(), BUDGET);
    let cases = std::env::var("AUREOLE_FUZZ_CASES")
        .ok()
        .and_then(|n| n.parse().ok())
        .unwrap_or(300);
    // A failure is a state of the server, not of one input: no shrinking.
    let mut runner = TestRunner::new(Config {
        cases,
        failure_persistence: None,
        max_shrink_iters: 0,
        ..Config::default()
    });
    let strategy = request(addr, image.display().to_string());
    let answers = std::sync::Mutex::new(std::collections::BTreeMap::new());
    runner
        .run(&strategy, |request| {
            let answer = send(addr, &request);
            if std::env::var_os("AUREOLE_FUZZ_VERBOSE").is_some() {
                let peak = peak_memory().unwrap_or(0) >> 20;
                println!("{request:?}\n  -> {answer:?}, peak {peak} MB");
            }
            let status = answer.as_ref().map(|(status, _)| *status);
            // Exports run on after their answer: the one that overran may be
            // named a request or two late.
            if let Some(peak) = peak_memory() {
                prop_assert!(
                    peak < LIMIT,
                    "peak memory {} MB (budget {} MB) after {request:?}",
                    peak >> 20,
                    BUDGET >> 20
                );
            }
            let endpoint = request.path.split('?').next().unwrap_or("").to_string();
            let key = (endpoint.chars().take(20).collect::<String>(), status);
            *answers.lock().unwrap().entry(key).or_insert(0) += 1;
            let allowed = status.is_some_and(|s| {
                (200..300).contains(&s) || s == 303 || (400..500).contains(&s) || s == 503
            });
            prop_assert!(allowed, "answer {status:?} to {request:?}");
            Ok(())
        })
        .unwrap();
    // What was tried, for whoever reads the log (`--nocapture`).
    for ((endpoint, status), count) in answers.into_inner().unwrap() {
        println!("{endpoint:20} {status:?}: {count}");
    }

    // Still serving, and what it made stayed within its budget (the test's
    // own memory and the server's code beside it).
    let status = send(
        addr,
        &Request {
            method: "GET".into(),
            path: "/api/status".into(),
            headers: vec![
                ("Host".into(), addr.to_string()),
                ("Authorization".into(), format!("Bearer {TOKEN}")),
            ],
            body: Vec::new(),
        },
    );
    assert_eq!(status.map(|(status, _)| status), Some(200));
    if let Some(peak) = peak_memory() {
        assert!(
            peak < LIMIT,
            "peak memory {} MB over a budget of {} MB",
            peak >> 20,
            BUDGET >> 20
        );
    }
}
