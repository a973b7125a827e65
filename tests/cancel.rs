//! A fit whose cancellation flag is set stops before reading any chunk and says so.

use std::path::Path;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

use mrsysid::error::RequestError;
use mrsysid::{Error, Identification, Vehicle};

#[test]
fn a_set_flag_stops_the_fit_before_the_first_chunk() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let vehicle =
        Vehicle::from_toml_file(&root.join("data/vehicles/quad_x.toml")).expect("vehicle");
    let flag = Arc::new(AtomicBool::new(true));
    let read = Arc::new(AtomicU64::new(0));
    let run = Identification::new(vehicle)
        .log(root.join("data/quad_x_sweep.csv"))
        .threads(1)
        .progress(read.clone())
        .cancel(flag)
        .run();
    assert!(
        matches!(run, Err(Error::Request(RequestError::Cancelled))),
        "{run:?}"
    );
    assert_eq!(read.load(Ordering::Relaxed), 0, "no chunk was passed on");
}
