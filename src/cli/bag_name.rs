//! The default bag folder name, as `ros2 bag record` names it:
//! `rosbag2_YYYY_MM_DD-HH_MM_SS` in UTC.

use std::path::PathBuf;

/// The (year, month 1-12, day 1-31) of `days` days after 1970-01-01 in the proleptic
/// Gregorian calendar (H. Hinnant's `civil_from_days`: eras of 400 years = 146 097
/// days, years starting on March 1 so that the leap day is the last day of a year).
fn civil_from_days(days: i64) -> (i64, u32, u32) {
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z.rem_euclid(146_097);
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = doy - (153 * mp + 2) / 5 + 1;
    let month = if mp < 10 { mp + 3 } else { mp - 9 };
    let year = yoe + era * 400 + (month <= 2) as i64;
    (year, month as u32, day as u32)
}

/// The folder name for a recording started `secs` seconds after the Unix epoch (UTC).
fn bag_folder_name(secs: i64) -> String {
    let (days, rem) = (secs.div_euclid(86_400), secs.rem_euclid(86_400));
    let (year, month, day) = civil_from_days(days);
    format!(
        "rosbag2_{year:04}_{month:02}_{day:02}-{:02}_{:02}_{:02}",
        rem / 3600,
        rem % 3600 / 60,
        rem % 60
    )
}

/// `--record` with or without a value: the given folder, or a new one named after the
/// current UTC time.
pub fn bag_folder(given: Option<PathBuf>) -> PathBuf {
    if let Some(given) = given {
        return given;
    }
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_secs() as i64)
        .unwrap_or(0);
    PathBuf::from(bag_folder_name(secs))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn civil_dates_at_known_days() {
        assert_eq!(civil_from_days(0), (1970, 1, 1));
        assert_eq!(civil_from_days(-1), (1969, 12, 31));
        // 2000 is a leap year (divisible by 400): Feb 29 exists, day 11 016
        assert_eq!(civil_from_days(11_016), (2000, 2, 29));
        assert_eq!(civil_from_days(11_017), (2000, 3, 1));
        // 2100 is not (divisible by 100 only): Feb 28 is followed by Mar 1
        assert_eq!(civil_from_days(47_540), (2100, 2, 28));
        assert_eq!(civil_from_days(47_541), (2100, 3, 1));
        assert_eq!(civil_from_days(20_789), (2026, 12, 2));
    }

    #[test]
    fn every_day_follows_the_previous_one() {
        // 1900-01-01 .. 2200-01-01: consecutive days differ by exactly one calendar day
        let days_in = |y: i64, m: u32| match m {
            2 if (y % 4 == 0 && y % 100 != 0) || y % 400 == 0 => 29,
            2 => 28,
            4 | 6 | 9 | 11 => 30,
            _ => 31,
        };
        let mut prev = civil_from_days(-25_567);
        assert_eq!(prev, (1900, 1, 1));
        for d in -25_566..84_000 {
            let next = civil_from_days(d);
            let expected = if prev.2 < days_in(prev.0, prev.1) {
                (prev.0, prev.1, prev.2 + 1)
            } else if prev.1 < 12 {
                (prev.0, prev.1 + 1, 1)
            } else {
                (prev.0 + 1, 1, 1)
            };
            assert_eq!(next, expected, "day {d}");
            prev = next;
        }
    }

    #[test]
    fn folder_names_as_ros2_bag_record() {
        // 2026-12-02 02:27:30 UTC
        let secs = 20_789 * 86_400 + 2 * 3600 + 27 * 60 + 30;
        assert_eq!(bag_folder_name(secs), "rosbag2_2026_12_02-02_27_30");
        assert_eq!(bag_folder_name(0), "rosbag2_1970_01_01-00_00_00");
        assert_eq!(
            bag_folder(Some(PathBuf::from("mine"))),
            PathBuf::from("mine")
        );
        assert!(bag_folder(None).to_string_lossy().starts_with("rosbag2_20"));
    }
}
