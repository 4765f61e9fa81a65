//! The IIO source: a Linux Industrial I/O accelerometer under `/sys/bus/iio/devices`
//! (tablets, convertible laptops), sampled at a steady rate.

use crate::protocol::Tilt;
use std::path::{Path, PathBuf};
use std::time::Duration;
use tokio::sync::mpsc::Sender;

/// Where Linux lists its IIO devices.
pub const IIO_ROOT: &str = "/sys/bus/iio/devices";

/// A Linux IIO accelerometer: `in_accel_{x,y,z}_raw`, plus `in_accel_offset` (if any), times
/// `in_accel_scale` (or per-axis `in_accel_{x,y,z}_scale`) gives m/s^2. The device's mount
/// matrix is not applied: readings are taken in the device's own frame.
#[derive(Clone, Debug)]
pub struct IioAccel {
    dir: PathBuf,
    scale: [f64; 3],
    offset: [f64; 3],
}

const AXES: [char; 3] = ['x', 'y', 'z'];

impl IioAccel {
    /// Open `device` (a directory, or a name like `iio:device0` under [`IIO_ROOT`]), or the
    /// first accelerometer under `root` when `device` is `None`.
    pub fn open(device: Option<&str>, root: &Path) -> Result<IioAccel, String> {
        let dir = match device {
            Some(d) if d.contains('/') => PathBuf::from(d),
            Some(d) => root.join(d),
            None => {
                let entries = std::fs::read_dir(root)
                    .map_err(|e| format!("no IIO devices: cannot list {}: {e}", root.display()))?;
                let mut dirs: Vec<PathBuf> = entries
                    .filter_map(|e| e.ok().map(|e| e.path()))
                    .filter(|p| p.join("in_accel_x_raw").exists())
                    .collect();
                dirs.sort();
                dirs.into_iter().next().ok_or_else(|| {
                    format!(
                        "no IIO accelerometer: no device under {} has in_accel_x_raw",
                        root.display()
                    )
                })?
            }
        };
        if !dir.join("in_accel_x_raw").exists() {
            return Err(format!(
                "{} is not an IIO accelerometer (no in_accel_x_raw there)",
                dir.display()
            ));
        }
        let read_opt = |name: &str| -> Result<Option<f64>, String> {
            let p = dir.join(name);
            if !p.exists() {
                return Ok(None);
            }
            read_number(&p).map(Some)
        };
        let common_scale = read_opt("in_accel_scale")?;
        let common_offset = read_opt("in_accel_offset")?.unwrap_or(0.0);
        let mut scale = [0.0; 3];
        let mut offset = [0.0; 3];
        for (i, a) in AXES.iter().enumerate() {
            scale[i] = match read_opt(&format!("in_accel_{a}_scale"))?.or(common_scale) {
                Some(s) => s,
                None => {
                    return Err(format!(
                        "{}: no in_accel_scale nor in_accel_{a}_scale",
                        dir.display()
                    ))
                }
            };
            offset[i] = read_opt(&format!("in_accel_{a}_offset"))?.unwrap_or(common_offset);
        }
        Ok(IioAccel { dir, scale, offset })
    }

    /// The device's directory.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// Read the three axes now.
    pub fn read(&self) -> Result<Tilt, String> {
        let mut v = [0f32; 3];
        for (i, a) in AXES.iter().enumerate() {
            let raw = read_number(&self.dir.join(format!("in_accel_{a}_raw")))?;
            v[i] = ((raw + self.offset[i]) * self.scale[i]) as f32;
        }
        Ok(Tilt::Accelerometer {
            x: v[0],
            y: v[1],
            z: v[2],
        })
    }
}

fn read_number(path: &Path) -> Result<f64, String> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    text.trim()
        .parse::<f64>()
        .ok()
        .filter(|v| v.is_finite())
        .ok_or_else(|| format!("{}: {:?} is not a number", path.display(), text.trim()))
}

/// Read `dev` every `1 / rate` s and send each reading that differs from the last; a read
/// error is logged once until it changes.
pub async fn read_iio(dev: IioAccel, rate: f64, tx: Sender<Tilt>) {
    let mut tick = tokio::time::interval(Duration::from_secs_f64(1.0 / rate));
    let mut last: Option<Tilt> = None;
    let mut last_error = String::new();
    loop {
        tick.tick().await;
        match dev.read() {
            Ok(t) if Some(t) != last => {
                last = Some(t);
                if tx.send(t).await.is_err() {
                    return;
                }
            }
            Ok(_) => {}
            Err(e) if e != last_error => {
                tracing::warn!("{e}");
                last_error = e;
            }
            Err(_) => {}
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::client::tilt::test_support::accel;

    #[test]
    fn iio_devices_are_read_and_absence_is_explained() {
        let root = std::env::temp_dir().join(format!("tiltbox-iio-{}", std::process::id()));
        let dev = root.join("iio:device3");
        std::fs::create_dir_all(&dev).unwrap();
        let e = IioAccel::open(None, &root).unwrap_err();
        assert!(e.contains("no IIO accelerometer"), "{e}");
        let e = IioAccel::open(None, &root.join("nothing")).unwrap_err();
        assert!(e.contains("no IIO devices"), "{e}");
        for (f, v) in [
            ("in_accel_x_raw", "0\n"),
            ("in_accel_y_raw", "-1000\n"),
            ("in_accel_z_raw", "20"),
            ("in_accel_scale", "0.00981\n"),
        ] {
            std::fs::write(dev.join(f), v).unwrap();
        }
        let a = IioAccel::open(None, &root).unwrap();
        let (x, y, z) = accel(Some(a.read().unwrap()));
        assert!(x == 0.0 && (y + 9.81).abs() < 1e-5 && (z - 0.1962).abs() < 1e-5);
        std::fs::write(dev.join("in_accel_y_raw"), "oops").unwrap();
        assert!(a.read().unwrap_err().contains("\"oops\" is not a number"));
        let _ = std::fs::remove_dir_all(root);
    }
}
