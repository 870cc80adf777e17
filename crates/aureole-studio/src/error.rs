//! What the studio refuses, as an HTTP status and one line of words.

use axum::http::StatusCode;
use axum::response::{IntoResponse, Response};

/// A refused request or a failed render.
#[derive(Debug, thiserror::Error)]
pub enum StudioError {
    /// The request is malformed or asks for what is not allowed.
    #[error("{0}")]
    BadRequest(String),
    /// A path outside the roots.
    #[error("{0}")]
    Forbidden(String),
    /// A file under the roots that is not there.
    #[error("{0}")]
    NotFound(String),
    /// A file that cannot be read as an image, or a frame that does not fit.
    #[error("{0}")]
    Unprocessable(String),
    /// The file asked for exists and may not be replaced.
    #[error("{0}")]
    Conflict(String),
    /// The studio's memory budget is taken by other jobs.
    #[error("{0}")]
    Busy(String),
    /// A newer render took its place.
    #[error("superseded by a newer render")]
    Superseded,
    /// Something went wrong on our side.
    #[error("{0}")]
    Internal(String),
}

impl StudioError {
    /// The HTTP status it is answered with.
    pub fn status(&self) -> StatusCode {
        match self {
            StudioError::BadRequest(_) => StatusCode::BAD_REQUEST,
            StudioError::Forbidden(_) => StatusCode::FORBIDDEN,
            StudioError::NotFound(_) => StatusCode::NOT_FOUND,
            StudioError::Unprocessable(_) => StatusCode::UNPROCESSABLE_ENTITY,
            StudioError::Conflict(_) => StatusCode::CONFLICT,
            StudioError::Busy(_) => StatusCode::SERVICE_UNAVAILABLE,
            StudioError::Superseded => StatusCode::CONFLICT,
            StudioError::Internal(_) => StatusCode::INTERNAL_SERVER_ERROR,
        }
    }
}

impl From<aureole::Error> for StudioError {
    fn from(error: aureole::Error) -> Self {
        use aureole::Error as E;
        match error {
            E::Cancelled => StudioError::Superseded,
            E::Memory { .. } | E::Allocation { .. } | E::BadSamples { .. } | E::Io { .. } => {
                StudioError::Unprocessable(error.to_string())
            }
            _ => StudioError::BadRequest(error.to_string()),
        }
    }
}

impl From<aureole_io::Error> for StudioError {
    fn from(error: aureole_io::Error) -> Self {
        StudioError::Unprocessable(error.to_string())
    }
}

impl IntoResponse for StudioError {
    fn into_response(self) -> Response {
        // One line, as the command line says it.
        let line = self.to_string().replace('\n', " ");
        let body = serde_json::json!({ "error": line }).to_string();
        (
            self.status(),
            [(axum::http::header::CONTENT_TYPE, "application/json")],
            body,
        )
            .into_response()
    }
}
