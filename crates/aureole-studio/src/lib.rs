//! # aureole-studio
//!
//! A local web studio over [aureole]'s session API: pick an image under
//! the allowed folders, tune the camera, and watch the light. The page, its
//! script and its style are compiled in; nothing is fetched at run time.
//!
//! The HTTP API the page uses, for scripts too. Every request carries the
//! token printed at start (see [`access`]).
//!
//! - `GET /api/presets`: `[{"name", "description", "toml"}]`.
//! - `GET /api/images`: `{"roots": [...], "images": [...]}`, the images
//!   under the roots.
//! - `POST /api/render` with a JSON [`render::RenderRequest`]: a PNG of the
//!   requested width (or, with `"format": "linear"`, its f32 R, G, B in
//!   cd/m²), with `X-Energy-In`, `X-Energy-Out`, `X-White`, `X-Render-Ms`,
//!   `X-Preview-Size`, `X-Full-Size`, `X-Scale`, `X-Luminance` (min, median,
//!   max of the full image) and `X-Auto-White-{Filmic,Reinhard,Clip}`
//!   headers; the kernel view adds `X-Profile-Radial` and
//!   `X-Profile-Angular`. `max_kernel` caps the kernel as `--max-kernel`
//!   does; `client` names the tab, whose newer render replaces its older.
//! - `POST /api/export`: the same fields and `output` (and `overwrite`):
//!   a job, followed at `GET /api/export/{id}` and cancelled by `DELETE`.
//! - `POST /api/command` with an export's fields: `{"argv", "text"}`, the
//!   command lines that write what that export writes.
//! - `POST /api/lens` with a config's TOML: the section (SVG) of the lens
//!   its ghosts are traced through.
//!
//! A refusal is a 4xx with `{"error": "one line"}`; a render that finds the
//! memory budget taken by exports for too long, a 503.

#![deny(unsafe_code)]
#![warn(missing_docs)]

pub mod access;
pub mod budget;
pub mod camera;
pub mod command;
pub mod error;
pub mod export;
pub mod interfaces;
pub mod render;
pub mod roots;

use aureole::Device;
use std::sync::Arc;

use axum::body::Bytes;
use axum::extract::{DefaultBodyLimit, Path, State};
use axum::http::header;
use axum::middleware;
use axum::response::{IntoResponse, Response};
use axum::routing::{get, post};
use axum::{Json, Router};

pub use access::Access;
pub use error::StudioError;
pub use render::{RenderRequest, Renderer};
pub use roots::Roots;

/// The largest request body: a config's TOML and a few numbers.
pub const MAX_BODY: usize = 1 << 20;

const INDEX: &str = include_str!("../assets/index.html");
/// The page's ES modules: the entry and what it imports.
const SCRIPTS: [(&str, &str); 4] = [
    ("/app.js", include_str!("../assets/app.js")),
    ("/common.js", include_str!("../assets/common.js")),
    ("/display.js", include_str!("../assets/display.js")),
    ("/panels.js", include_str!("../assets/panels.js")),
];
const STYLE: &str = include_str!("../assets/app.css");

/// What the routes share: who may drive the studio, previews and
/// full-resolution exports.
#[derive(Clone)]
pub struct Studio {
    access: Access,
    renderer: Arc<Renderer>,
    exports: Arc<export::Exports>,
}

impl Studio {
    /// A studio reading (and exporting) under `roots`, its renders and
    /// exports together within `memory_limit` bytes, convolving on
    /// `device`, driven by whoever `access` lets in.
    pub fn new(roots: Roots, memory_limit: u64, device: Device, access: Access) -> Studio {
        let budget = budget::Budget::new(memory_limit);
        let renderer = Arc::new(Renderer::new(roots.clone(), budget.clone(), device));
        // A job that would wait takes the memory of the kept preview
        // session first.
        let kept = Arc::downgrade(&renderer);
        budget.on_shortage(move || {
            if let Some(renderer) = kept.upgrade() {
                renderer.release_kept();
            }
        });
        Studio {
            access,
            renderer,
            exports: Arc::new(export::Exports::new(roots, budget, device)),
        }
    }
}

/// The studio's routes.
pub fn router(studio: Studio) -> Router {
    let mut router = Router::new();
    for (path, script) in SCRIPTS {
        router = router.route(
            path,
            get(move || async move { page(script, "text/javascript; charset=utf-8") }),
        );
    }
    router
        .route(
            "/",
            get(|| async { page(INDEX, "text/html; charset=utf-8") }),
        )
        .route(
            "/app.css",
            get(|| async { page(STYLE, "text/css; charset=utf-8") }),
        )
        .route("/api/presets", get(presets))
        .route("/api/images", get(images))
        .route("/api/schema", get(|| async { Json(camera::schema()) }))
        .route(
            "/api/status",
            get(|State(studio): State<Studio>| async move { Json(studio.renderer.status()) }),
        )
        .route("/api/config/read", post(read_config))
        .route("/api/config/write", post(write_config))
        .route("/api/lens", post(lens_picture))
        .route("/api/render", post(render_picture))
        .route("/api/export", post(start_export))
        .route("/api/command", post(command_lines))
        .route(
            "/api/export/{id}",
            get(export_progress).delete(cancel_export),
        )
        .layer(DefaultBodyLimit::max(MAX_BODY))
        .layer(middleware::from_fn_with_state(
            studio.access.clone(),
            access::gate,
        ))
        .with_state(studio)
}

/// Serves the studio on `listener` until the process ends.
pub async fn serve(listener: tokio::net::TcpListener, studio: Studio) -> std::io::Result<()> {
    axum::serve(listener, router(studio)).await
}

async fn read_config(body: Bytes) -> Result<Json<serde_json::Value>, StudioError> {
    let text = std::str::from_utf8(&body)
        .map_err(|_| StudioError::BadRequest("the config is not UTF-8 text".into()))?;
    camera::read(text).map(Json)
}

/// `POST /api/lens`: the picture (SVG) of the lens a config's ghosts are
/// traced through.
async fn lens_picture(body: Bytes) -> Result<Response, StudioError> {
    let text = std::str::from_utf8(&body)
        .map_err(|_| StudioError::BadRequest("the config is not UTF-8 text".into()))?;
    let config = render::parse_config(text)?;
    let Some(ghosts) = &config.ghosts else {
        return Err(StudioError::BadRequest(
            "config: no lens to draw: it has no [[effect]] of type = \"ghosts\"".into(),
        ));
    };
    Ok((
        [(header::CONTENT_TYPE, "image/svg+xml")],
        aureole_io::lens_drawing::svg(&ghosts.lens.lens),
    )
        .into_response())
}

async fn write_config(body: Bytes) -> Result<Response, StudioError> {
    let value: serde_json::Value = serde_json::from_slice(&body)
        .map_err(|e| StudioError::BadRequest(format!("the camera: {e}")))?;
    let text = camera::write(value)?;
    Ok((
        [(header::CONTENT_TYPE, "application/toml; charset=utf-8")],
        text,
    )
        .into_response())
}

async fn start_export(
    State(studio): State<Studio>,
    body: Bytes,
) -> Result<Json<serde_json::Value>, StudioError> {
    let request = export::ExportRequest::from_json(&body)?;
    let id = studio.exports.start(request)?;
    Ok(Json(serde_json::json!({ "job": id })))
}

async fn command_lines(body: Bytes) -> Result<Json<command::Commands>, StudioError> {
    let request = export::ExportRequest::from_json(&body)?;
    command::for_export(&request).map(Json)
}

async fn export_progress(
    State(studio): State<Studio>,
    Path(id): Path<u64>,
) -> Result<Json<export::Progress>, StudioError> {
    studio
        .exports
        .progress(id)
        .map(Json)
        .ok_or_else(|| StudioError::NotFound(format!("no export {id}")))
}

async fn cancel_export(
    State(studio): State<Studio>,
    Path(id): Path<u64>,
) -> Result<Json<serde_json::Value>, StudioError> {
    if studio.exports.cancel(id) {
        Ok(Json(serde_json::json!({ "cancelled": id })))
    } else {
        Err(StudioError::NotFound(format!("no export {id}")))
    }
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

async fn images(State(studio): State<Studio>) -> Json<serde_json::Value> {
    let roots = studio.renderer.roots().clone();
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
    State(studio): State<Studio>,
    body: Bytes,
) -> Result<Response, StudioError> {
    let request: RenderRequest = serde_json::from_slice(&body)
        .map_err(|e| StudioError::BadRequest(format!("the render request: {e}")))?;
    let renderer = studio.renderer.clone();
    // When the page goes away (a closed tab) axum drops this future: the
    // guard then stops the render within the session's next check.
    let cancel = aureole::Cancel::new();
    let guard = CancelOnDrop(Some(cancel.clone()));
    let rendered = tokio::task::spawn_blocking(move || renderer.render(&request, cancel))
        .await
        .map_err(|e| StudioError::Internal(e.to_string()))??;
    guard.disarm();
    let headers = [
        (header::CONTENT_TYPE, rendered.content_type.to_string()),
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
            "x-full-size",
            format!("{}x{}", rendered.full.size.0, rendered.full.size.1),
        ),
        ("x-scale", format!("{}", rendered.full.scale)),
        (
            "x-luminance",
            format!(
                "{:.6e} {:.6e} {:.6e}",
                rendered.full.luminance[0], rendered.full.luminance[1], rendered.full.luminance[2]
            ),
        ),
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
    if let Some((radial, angular)) = &rendered.profiles {
        let list = |values: &[f64]| {
            values
                .iter()
                .map(|v| format!("{v:.3e}"))
                .collect::<Vec<_>>()
                .join(",")
        };
        for (name, values) in [("x-profile-radial", radial), ("x-profile-angular", angular)] {
            if let Ok(value) = header::HeaderValue::from_str(&list(values)) {
                extra.insert(name, value);
            }
        }
    }
    Ok(response)
}

/// A mutex's guard, also after a thread panicked holding it: the studio's
/// caches and jobs stay usable, as a failed render leaves the server
/// running.
pub(crate) fn locked<T>(mutex: &std::sync::Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    mutex
        .lock()
        .unwrap_or_else(|poisoned| poisoned.into_inner())
}

/// Cancels a render when dropped before [`CancelOnDrop::disarm`].
struct CancelOnDrop(Option<aureole::Cancel>);

impl CancelOnDrop {
    fn disarm(mut self) {
        self.0 = None;
    }
}

impl Drop for CancelOnDrop {
    fn drop(&mut self) {
        if let Some(cancel) = &self.0 {
            cancel.cancel();
        }
    }
}
