//! Calendar dates to days since the Unix epoch, for the sensors that stamp packets with a UTC
//! date (Hesai, Livox with GPS time).

/// Days from 1970-01-01 to the date (proleptic Gregorian; H. Hinnant's `days_from_civil`).
pub const fn days_from_civil(year: i64, month: u8, day: u8) -> i64 {
    let y = if month <= 2 { year - 1 } else { year };
    let era = y.div_euclid(400);
    let yoe = y - era * 400;
    let m = month as i64;
    let doy = (153 * (if m > 2 { m - 3 } else { m + 9 }) + 2) / 5 + day as i64 - 1;
    let doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
    era * 146_097 + doe - 719_468
}

/// Days in `month` of `year`.
pub const fn days_in_month(year: i64, month: u8) -> u8 {
    let leap = (year % 4 == 0 && year % 100 != 0) || year % 400 == 0;
    match month {
        2 if leap => 29,
        2 => 28,
        4 | 6 | 9 | 11 => 30,
        _ => 31,
    }
}

/// [`days_from_civil`] of a date that exists, on or after 1970-01-01; `None` otherwise.
pub const fn days_from_civil_checked(year: i64, month: u8, day: u8) -> Option<i64> {
    if year < 1970 || month < 1 || month > 12 || day < 1 || day > days_in_month(year, month) {
        return None;
    }
    Some(days_from_civil(year, month, day))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn civil_days_match_known_dates() {
        assert_eq!(days_from_civil(1970, 1, 1), 0);
        assert_eq!(days_from_civil(2000, 3, 1), 11_017);
        assert_eq!(days_from_civil(2024, 9, 17), 19_983);
        assert_eq!(
            days_from_civil(2024, 2, 29) + 1,
            days_from_civil(2024, 3, 1)
        );
        assert_eq!(days_in_month(2023, 2), 28);
        assert_eq!(days_in_month(2000, 2), 29);
        assert_eq!(days_in_month(1900, 2), 28);
        assert_eq!(days_in_month(2023, 4), 30);
        assert_eq!(days_from_civil_checked(2023, 2, 29), None);
        assert_eq!(days_from_civil_checked(2023, 13, 1), None);
        assert_eq!(days_from_civil_checked(2023, 0, 1), None);
        assert_eq!(days_from_civil_checked(2023, 1, 0), None);
        assert_eq!(days_from_civil_checked(1969, 12, 31), None);
        assert_eq!(days_from_civil_checked(2024, 9, 17), Some(19_983));
    }
}
