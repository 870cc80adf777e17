//! The GPU engine on the issue-5 workload, beside the CPU engine in the
//! same run: the steady state of a plan whose kernel spectra are on the
//! device, frame planes up and results down included. `AUREOLE_BENCH_4K=1`
//! adds the 4K frame (on a software adapter it takes minutes).

mod workload;

use std::hint::black_box;
use std::time::Duration;

use aureole::{ApplyOptions, Device, Plan};
use criterion::{criterion_group, criterion_main, Criterion};

fn steady(c: &mut Criterion) {
    let mut sizes = vec![("1080p", 1920, 1080)];
    if std::env::var_os("AUREOLE_BENCH_4K").is_some() {
        sizes.push(("4k", 3840, 2160));
    }
    let mut group = c.benchmark_group("device");
    group
        .sample_size(10)
        .measurement_time(Duration::from_secs(20));
    for (name, w, h) in sizes {
        let image = workload::image(w, h);
        let kernel = Plan::for_image(&workload::config(), w, h, None)
            .expect("workload plan")
            .into_kernel();
        for device in [Device::Cpu, Device::Gpu] {
            let plan = match Plan::with_kernel_on(kernel.clone(), (w, h), device) {
                Ok(plan) => plan,
                Err(why) => {
                    eprintln!("{name} on {}: skipped, {why}", device.name());
                    continue;
                }
            };
            eprintln!("{name}: {}", plan.device());
            group.bench_function(format!("{name}-{}", device.name()), |b| {
                b.iter(|| black_box(plan.apply(&image, 1.0, &ApplyOptions::default(), &mut |_| {})))
            });
        }
    }
    group.finish();
}

criterion_group!(benches, steady);
criterion_main!(benches);
