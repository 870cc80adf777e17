//! What the studio's tests share: a real server on a port of its own. Each
//! test binary uses a part of it, hence the allowance below.
#![allow(dead_code)]

use std::net::SocketAddr;
use std::path::{Path, PathBuf};

use aureole_studio::{Access, Roots, Studio};

/// The token of the tests' servers.
pub const TOKEN: &str = "a-token-for-the-tests";

/// The demo night street of `width`×`height` written to `dir/name` as an
/// EXR; its path.
pub fn street(dir: &Path, name: &str, (width, height): (usize, usize)) -> PathBuf {
    let path = dir.join(name);
    aureole_io::write::write_linear(
        &path,
        &aureole_io::demo::night_street(width, height),
        Default::default(),
    )
    .unwrap();
    path
}

/// A server reading from `root`, on an ephemeral port, for the test's life.
pub fn server(root: &Path) -> SocketAddr {
    server_within(root, 4 << 30)
}

/// A server whose renders and exports share `memory` bytes.
pub fn server_within(root: &Path, memory: u64) -> SocketAddr {
    let roots = Roots::new(&[root.to_path_buf()]).unwrap();
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let runtime = tokio::runtime::Builder::new_multi_thread()
            .worker_threads(2)
            .enable_all()
            .build()
            .unwrap();
        runtime.block_on(async {
            let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
            let bound = listener.local_addr().unwrap();
            let studio = Studio::new(
                roots,
                memory,
                aureole::Device::Cpu,
                Access::with_token(bound, TOKEN.into()),
            );
            tx.send(bound).unwrap();
            aureole_studio::serve(listener, studio).await.unwrap();
        });
    });
    rx.recv().unwrap()
}
