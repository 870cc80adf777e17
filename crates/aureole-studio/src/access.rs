//! Who may drive the studio: the user who started it, as Jupyter decides
//! it. The studio is a server on the user's machine, and every web page
//! their browser opens can send it requests; so every request must carry
//! the secret token made at start (a cookie the page keeps, the `token`
//! query parameter or an `Authorization: Bearer` header), name the
//! studio's own address as its `Host` (a DNS-rebinding page names its own
//! domain) and, when the browser says where it comes from, come from the
//! studio's own page (`Origin`). Every answer forbids framing and loading
//! from elsewhere.

use std::net::{IpAddr, SocketAddr};

use axum::extract::{Request, State};
use axum::http::{header, HeaderMap, HeaderValue, Method, StatusCode};
use axum::middleware::Next;
use axum::response::{IntoResponse, Response};

use crate::error::StudioError;

/// The page's own scripts, styles and requests only; no framing.
const CONTENT_SECURITY_POLICY: &str = "default-src 'none'; script-src 'self'; style-src 'self'; \
img-src 'self' blob: data:; connect-src 'self'; frame-ancestors 'none'; base-uri 'none'; \
form-action 'none'";

/// The token and the addresses of one studio.
#[derive(Clone)]
pub struct Access {
    token: String,
    /// `Host` values that name this studio: loopback names and the listen
    /// address, each with the port.
    hosts: Vec<String>,
    /// The cookie that keeps the token, one per port: cookies do not tell
    /// ports apart, and two studios may run side by side.
    cookie: String,
}

impl Access {
    /// A new random token (256 bits from the operating system) for a studio
    /// listening on `bound`.
    pub fn new(bound: SocketAddr) -> Result<Access, StudioError> {
        let mut bytes = [0u8; 32];
        getrandom::fill(&mut bytes)
            .map_err(|e| StudioError::Internal(format!("no random token: {e}")))?;
        let token = bytes.iter().map(|b| format!("{b:02x}")).collect();
        Ok(Access::with_token(bound, token))
    }

    /// An access with a given token (tests, and a user who sets one).
    pub fn with_token(bound: SocketAddr, token: String) -> Access {
        let port = bound.port();
        let mut hosts = vec![
            format!("127.0.0.1:{port}"),
            format!("localhost:{port}"),
            format!("[::1]:{port}"),
        ];
        let listened = std::iter::once(bound.ip());
        for address in listened.chain(reached_at(bound)) {
            let own = SocketAddr::new(address, port).to_string();
            if !hosts.contains(&own) {
                hosts.push(own);
            }
        }
        if bound.ip().is_unspecified() {
            // The machine's own name: a rebinding page names its own domain.
            if let Some(name) = crate::interfaces::host_name() {
                hosts.push(format!("{name}:{port}"));
            }
        }
        Access {
            token,
            hosts,
            cookie: format!("aureole-studio-{port}"),
        }
    }

    /// The token.
    pub fn token(&self) -> &str {
        &self.token
    }

    /// The address to open: the page, with the token, on `bound`; on
    /// every interface (0.0.0.0, ::), at this machine's first address that
    /// other machines reach, else the loopback.
    pub fn url(&self, bound: SocketAddr) -> String {
        self.urls(bound)
            .into_iter()
            .next()
            .unwrap_or_else(|| format!("http://{bound}/?token={}", self.token))
    }

    /// Every address the page opens at from `bound`: itself, or on every
    /// interface each of the machine's addresses, those other machines
    /// reach first.
    pub fn urls(&self, bound: SocketAddr) -> Vec<String> {
        let mut addresses = reached_at(bound);
        addresses.sort_by_key(IpAddr::is_loopback);
        addresses
            .into_iter()
            .map(|ip| {
                format!(
                    "http://{}/?token={}",
                    SocketAddr::new(ip, bound.port()),
                    self.token
                )
            })
            .collect()
    }

    fn host_allowed(&self, host: &str) -> bool {
        self.hosts.iter().any(|h| h.eq_ignore_ascii_case(host))
    }

    /// The token the request carries, from its header, query or cookie.
    fn presented<'a>(&self, headers: &'a HeaderMap, query: Option<&'a str>) -> Vec<&'a str> {
        let mut found = Vec::new();
        if let Some(bearer) = headers
            .get(header::AUTHORIZATION)
            .and_then(|v| v.to_str().ok())
            .and_then(|v| v.strip_prefix("Bearer "))
        {
            found.push(bearer.trim());
        }
        if let Some(token) = query.and_then(query_token) {
            found.push(token);
        }
        for cookies in headers.get_all(header::COOKIE) {
            let Ok(cookies) = cookies.to_str() else {
                continue;
            };
            for pair in cookies.split(';') {
                if let Some((name, value)) = pair.trim().split_once('=') {
                    if name == self.cookie {
                        found.push(value);
                    }
                }
            }
        }
        found
    }

    fn token_matches(&self, presented: &[&str]) -> bool {
        presented
            .iter()
            .any(|t| same(t.as_bytes(), self.token.as_bytes()))
    }
}

/// The addresses a listener on `bound` is reached at: its own, or on every
/// interface (0.0.0.0 or ::) the machine's (IPv4 ones alone for 0.0.0.0).
fn reached_at(bound: SocketAddr) -> Vec<IpAddr> {
    let ip = bound.ip();
    if !ip.is_unspecified() {
        return vec![ip];
    }
    let mut found: Vec<IpAddr> = crate::interfaces::addresses()
        .into_iter()
        .filter(|a| ip.is_ipv6() || a.is_ipv4())
        // Link-local IPv6 needs a zone in a URL, which no Host carries.
        .filter(|a| !matches!(a, IpAddr::V6(v6) if v6.is_unicast_link_local()))
        .collect();
    if found.is_empty() {
        found.push(if ip.is_ipv4() {
            IpAddr::from([127, 0, 0, 1])
        } else {
            IpAddr::from(std::net::Ipv6Addr::LOCALHOST)
        });
    }
    found
}

/// The `token` parameter of a query string.
fn query_token(query: &str) -> Option<&str> {
    query
        .split('&')
        .find_map(|pair| pair.strip_prefix("token="))
}

/// The query without its `token` parameter.
fn without_token(query: &str) -> String {
    query
        .split('&')
        .filter(|pair| !pair.starts_with("token=") && !pair.is_empty())
        .collect::<Vec<_>>()
        .join("&")
}

/// Equal bytes, in a time that does not depend on where they differ.
fn same(a: &[u8], b: &[u8]) -> bool {
    a.len() == b.len() && a.iter().zip(b).fold(0u8, |d, (x, y)| d | (x ^ y)) == 0
}

fn refuse(status: StatusCode, line: String) -> Response {
    let body = serde_json::json!({ "error": line }).to_string();
    (status, [(header::CONTENT_TYPE, "application/json")], body).into_response()
}

/// The routes' gate: checks `Host`, `Origin`, the token and a JSON body's
/// type, sets the token's cookie when the page is opened with it, and adds
/// the headers that keep other sites from framing or reading the page.
pub async fn gate(State(access): State<Access>, request: Request, next: Next) -> Response {
    let mut response = check(&access, request, next).await;
    let headers = response.headers_mut();
    for (name, value) in [
        ("x-frame-options", "DENY"),
        ("content-security-policy", CONTENT_SECURITY_POLICY),
        ("x-content-type-options", "nosniff"),
        ("referrer-policy", "no-referrer"),
        ("cross-origin-resource-policy", "same-origin"),
    ] {
        headers.insert(name, HeaderValue::from_static(value));
    }
    response
}

async fn check(access: &Access, request: Request, next: Next) -> Response {
    let headers = request.headers();
    let host = headers
        .get(header::HOST)
        .and_then(|v| v.to_str().ok())
        .unwrap_or("");
    if !access.host_allowed(host) {
        return refuse(
            StatusCode::FORBIDDEN,
            format!(
                "Host {host:?} is not this studio's address ({}): refused, as a page of another site that points its name here would be",
                access.hosts.join(", ")
            ),
        );
    }
    if let Some(origin) = headers.get(header::ORIGIN) {
        let own = format!("http://{host}");
        if origin.to_str().ok() != Some(own.as_str()) {
            return refuse(
                StatusCode::FORBIDDEN,
                format!(
                    "a request from {:?}, another site's page, is refused: only the studio's own page ({own}) may drive it",
                    origin.to_str().unwrap_or("?")
                ),
            );
        }
    }
    let query = request.uri().query();
    let presented = access.presented(headers, query);
    if !access.token_matches(&presented) {
        let line = if presented.is_empty() {
            "no token: open the address `aureole studio` printed (…/?token=…), or send the token as `Authorization: Bearer TOKEN` or `?token=TOKEN`"
        } else {
            "wrong token: open the address `aureole studio` printed, or send the token it printed"
        };
        return refuse(StatusCode::FORBIDDEN, line.to_string());
    }
    let page = request.method() == Method::GET && request.uri().path() == "/";
    if page {
        if let Some(query) = query.filter(|q| query_token(q).is_some()) {
            // The page keeps the token in a cookie, and the address bar,
            // history and screenshots lose it.
            let rest = without_token(query);
            let location = if rest.is_empty() {
                "/".to_string()
            } else {
                format!("/?{rest}")
            };
            let cookie = format!(
                "{}={}; Path=/; HttpOnly; SameSite=Strict",
                access.cookie, access.token
            );
            let mut response = StatusCode::SEE_OTHER.into_response();
            for (name, value) in [(header::LOCATION, location), (header::SET_COOKIE, cookie)] {
                if let Ok(value) = HeaderValue::from_str(&value) {
                    response.headers_mut().insert(name, value);
                }
            }
            return response;
        }
    }
    if request.method() == Method::POST && takes_json(request.uri().path()) {
        let json = headers
            .get(header::CONTENT_TYPE)
            .and_then(|v| v.to_str().ok())
            .and_then(|v| v.split(';').next())
            .is_some_and(|v| v.trim().eq_ignore_ascii_case("application/json"));
        if !json {
            return refuse(
                StatusCode::UNSUPPORTED_MEDIA_TYPE,
                format!(
                    "{}: send the request as JSON, with Content-Type: application/json",
                    request.uri().path()
                ),
            );
        }
    }
    next.run(request).await
}

/// The routes whose body is JSON.
fn takes_json(path: &str) -> bool {
    matches!(path, "/api/render" | "/api/export" | "/api/config/write")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tokens_compare_whole() {
        assert!(same(b"abc", b"abc"));
        assert!(!same(b"abc", b"abd"));
        assert!(!same(b"abc", b"ab"));
        assert!(!same(b"", b"a"));
    }

    #[test]
    fn the_token_leaves_the_query_and_the_rest_stays() {
        assert_eq!(query_token("image=a.exr&token=xyz"), Some("xyz"));
        assert_eq!(query_token("image=a.exr"), None);
        assert_eq!(
            without_token("token=xyz&image=a.exr&view=split"),
            "image=a.exr&view=split"
        );
        assert_eq!(without_token("token=xyz"), "");
    }

    #[test]
    fn loopback_names_and_the_listen_address_are_hosts() {
        let access = Access::with_token("192.168.1.5:8000".parse().unwrap(), "t".into());
        for host in [
            "127.0.0.1:8000",
            "LOCALHOST:8000",
            "[::1]:8000",
            "192.168.1.5:8000",
        ] {
            assert!(access.host_allowed(host), "{host}");
        }
        for host in ["evil.test:8000", "127.0.0.1:8001", "localhost", ""] {
            assert!(!access.host_allowed(host), "{host}");
        }
    }

    #[test]
    fn on_every_interface_the_machines_own_addresses_are_hosts_and_printed() {
        let access = Access::with_token("0.0.0.0:8000".parse().unwrap(), "t".into());
        let own: Vec<IpAddr> = crate::interfaces::addresses()
            .into_iter()
            .filter(IpAddr::is_ipv4)
            .collect();
        assert!(!own.is_empty());
        for ip in &own {
            let host = SocketAddr::new(*ip, 8000).to_string();
            assert!(access.host_allowed(&host), "{host}");
        }
        if let Some(name) = crate::interfaces::host_name() {
            assert!(access.host_allowed(&format!("{name}:8000")));
        }
        for host in ["evil.test:8000", "0.0.0.1:8000", "10.255.255.254:8001"] {
            assert!(!access.host_allowed(host), "{host}");
        }
        // The address printed first is one other machines reach, where
        // there is one; 0.0.0.0 is never printed.
        let urls = access.urls("0.0.0.0:8000".parse().unwrap());
        assert_eq!(urls.len(), own.len());
        assert!(urls.iter().all(|u| !u.contains("0.0.0.0")), "{urls:?}");
        if own.iter().any(|ip| !ip.is_loopback()) {
            assert!(!urls[0].contains("127.0.0.1"), "{urls:?}");
        }
        let access = Access::with_token("[::]:8000".parse().unwrap(), "t".into());
        assert!(access.host_allowed("[::1]:8000") && access.host_allowed("127.0.0.1:8000"));
    }

    #[test]
    fn tokens_are_random_and_long() {
        let bound: SocketAddr = "127.0.0.1:1".parse().unwrap();
        let (a, b) = (Access::new(bound).unwrap(), Access::new(bound).unwrap());
        assert_ne!(a.token(), b.token());
        assert_eq!(a.token().len(), 64);
    }
}
