//! # aureole-studio
//!
//! A local web studio over [aureole]'s session API: pick an image under
//! the allowed folders, tune the camera, and watch the light. The page, its
//! script and its style are compiled in; nothing is fetched at run time.
//!
//! The HTTP API the page uses, for scripts too:
//!
//! - `GET /api/presets`: `[{"name", "description", "toml"}]`.
//! - `GET /api/images`: `{"roots": [...], "images": [...]}`, the images
//!   under the roots.
//! - `POST /api/render` with a JSON [`render::RenderRequest`]: a PNG of the
//!   requested width (or, with `"format": "linear"`, its f32 R, G, B in
//!   cd/m²), with `X-Energy-In`, `X-Energy-Out`, `X-White`, `X-Render-Ms`,
//!   `X-Preview-Size` and `X-Auto-White-{Filmic,Reinhard,Clip}` headers. A
//!   refusal is a 4xx with `{"error": "one line"}`.

#![deny(unsafe_code)]
#![warn(missing_docs)]

pub mod error;
pub mod render;
pub mod roots;

use std::sync::Arc;

use axum::body::Bytes;
use axum::extract::{DefaultBodyLimit, State};
use axum::http::header;
use axum::response::{IntoResponse, Response};
use axum::routing::{get, post};
use axum::{Json, Router};

pub use error::StudioError;
pub use render::{RenderRequest, Renderer};
pub use roots::Roots;

/// The largest request body: a config's TOML and a few numbers.
pub const MAX_BODY: usize = 1 << 20;

const INDEX: &str = include_str!("../assets/index.html");
const SCRIPT: &str = include_str!("../assets/app.js");
const STYLE: &str = include_str!("../assets/app.css");

/// The studio's routes, rendering with `renderer`.
pub fn router(renderer: Arc<Renderer>) -> Router {
    Router::new()
        .route(
            "/",
            get(|| async { page(INDEX, "text/html; charset=utf-8") }),
        )
        .route(
            "/app.js",
            get(|| async { page(SCRIPT, "text/javascript; charset=utf-8") }),
        )
        .route(
            "/app.css",
            get(|| async { page(STYLE, "text/css; charset=utf-8") }),
        )
        .route("/api/presets", get(presets))
        .route("/api/images", get(images))
        .route("/api/render", post(render_picture))
        .layer(DefaultBodyLimit::max(MAX_BODY))
        .with_state(renderer)
}

/// Serves the studio on `listener` until the process ends.
pub async fn serve(
    listener: tokio::net::TcpListener,
    renderer: Arc<Renderer>,
) -> std::io::Result<()> {
    axum::serve(listener, router(renderer)).await
}

fn page(text: &'static str, kind: &'static str) -> Response {
    ([(header::CONTENT_TYPE, kind)], text).into_response()
}

async fn presets() -> Json<serde_json::Value> {
    let list: Vec<serde_json::Value> = aureole::presets::PRESETS
        .iter()
        .map(|p| {
            serde_json::json!({
                "name": p.name,
                "description": p.description(),
                "toml": p.toml,
            })
        })
        .collect();
    Json(serde_json::Value::Array(list))
}

async fn images(State(renderer): State<Arc<Renderer>>) -> Json<serde_json::Value> {
    let roots = renderer.roots().clone();
    let list = tokio::task::spawn_blocking(move || {
        let images: Vec<String> = roots
            .images()
            .iter()
            .map(|p| p.display().to_string())
            .collect();
        let folders: Vec<String> = roots
            .folders()
            .iter()
            .map(|p| p.display().to_string())
            .collect();
        serde_json::json!({ "roots": folders, "images": images, "demo": render::DEMO })
    })
    .await
    .unwrap_or_default();
    Json(list)
}

async fn render_picture(
    State(renderer): State<Arc<Renderer>>,
    body: Bytes,
) -> Result<Response, StudioError> {
    let request: RenderRequest = serde_json::from_slice(&body)
        .map_err(|e| StudioError::BadRequest(format!("the render request: {e}")))?;
    let rendered = tokio::task::spawn_blocking(move || renderer.render(&request))
        .await
        .map_err(|e| StudioError::Internal(e.to_string()))??;
    let kind = if rendered.is_png {
        "image/png"
    } else {
        "application/octet-stream"
    };
    let headers = [
        (header::CONTENT_TYPE, kind.to_string()),
        (header::CACHE_CONTROL, "no-store".to_string()),
    ];
    let mut response = (headers, rendered.bytes).into_response();
    let extra = response.headers_mut();
    for (name, value) in [
        ("x-energy-in", format!("{:.6e}", rendered.energy_in)),
        ("x-energy-out", format!("{:.6e}", rendered.energy_out)),
        ("x-white", format!("{:.6}", rendered.white)),
        ("x-render-ms", format!("{:.1}", rendered.milliseconds)),
        (
            "x-auto-white-filmic",
            format!("{:.6e}", rendered.auto_white[0]),
        ),
        (
            "x-auto-white-reinhard",
            format!("{:.6e}", rendered.auto_white[1]),
        ),
        (
            "x-auto-white-clip",
            format!("{:.6e}", rendered.auto_white[2]),
        ),
        (
            "x-preview-size",
            format!("{}x{}", rendered.width, rendered.height),
        ),
    ] {
        if let Ok(value) = header::HeaderValue::from_str(&value) {
            extra.insert(name, value);
        }
    }
    Ok(response)
}
