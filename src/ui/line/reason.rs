//! A failed step's reason in 中文: the station's typed [`Reason`] said from its values (the
//! value out of its limits with its unit and limits, the hardware code refused, the check that
//! failed). Wire names (CMD_VERSION, MSP_SET_AUTO_TEST_RESULT), field idents and numbers stay
//! as they are; what the operating system said is quoted as it came.

use crate::ops::station::Reason;
use crate::ui::zh::Zh;

impl Zh for Reason {
    fn zh(&self) -> String {
        match self {
            Reason::HardwareNotAllowed { hw } => format!("硬件型号 {hw:#04x} 不在允许之列"),
            Reason::FirmwareNotAllowed { firmware } => format!("固件版本 {firmware} 不在允许之列"),
            Reason::NoAnswer => "设备无应答".into(),
            Reason::NoAnswerHeldUp => "设备无应答,本机当时被拖慢(电脑负载过高)".into(),
            Reason::NoAnswerTo { command } => format!("{command} 无应答"),
            Reason::LinkLost => "连接中断".into(),
            Reason::LinkLostBecause { why } => {
                format!("连接中断:{}", crate::ui::zh::lost_port(why))
            }
            Reason::LinkLostDuring { step_zh, .. } => format!("{step_zh} 中连接中断"),
            Reason::Cancelled => "已停止".into(),
            Reason::OperatorAborted => "操作员中止".into(),
            Reason::NotAnsweredInTime => "操作员未在时限内回答".into(),
            Reason::OperatorSaidNo => "操作员回答“否”".into(),
            Reason::NotYesNo => "回答不是“是”或“否”".into(),
            Reason::NoSerialScanned => "未扫描序列号".into(),
            Reason::SerialMismatch => "序列号与规定格式不符".into(),
            Reason::NotAValue => "未输入数值".into(),
            Reason::NotANumber => "输入的不是数字".into(),
            Reason::OutOfLimits { values } => {
                let each: Vec<String> = values.iter().map(out_of_limits).collect();
                format!("超出限值:{}", each.join(";"))
            }
            Reason::UnexpectedValue { fields } => format!("读数不符:{}", fields.join(", ")),
            Reason::NotToggled { field } => format!("{field} 未被触发"),
            Reason::NoServo => "没有舵机".into(),
            Reason::NotRun => "未运行".into(),
            Reason::ProductInfoUnreadable => "产品信息(0x01)无法解读".into(),
            Reason::DataPointsMissing => "数据点缺失或数值不可能".into(),
            Reason::NoResultCommand => "设备配置没有 MSP_SET_AUTO_TEST_RESULT".into(),
            Reason::ReadBackDiffers { fields } if fields.is_empty() => "回读值与写入值不同".into(),
            Reason::ReadBackDiffers { fields } => {
                format!("回读值与写入值不同:{}", fields.join(", "))
            }
            Reason::Conformance { id, name } => {
                format!("一致性检查未通过:{}", conform_check_zh(id).unwrap_or(name))
            }
            Reason::Provision { step, why } => {
                let step = crate::ops::servo::provision::step::said(step).zh;
                format!("{step}:{}", provision_zh(why))
            }
            Reason::Error(e) => e.zh(),
            Reason::Other(words) => words.clone(),
        }
    }
}

/// One value out of its limits: `spray current 0.1 A(允许 0.2 至 1.5 A)`.
fn out_of_limits(m: &crate::ops::records::Measurement) -> String {
    let unit = if m.unit.is_empty() {
        String::new()
    } else {
        format!(" {}", m.unit)
    };
    let allowed = match (m.low, m.high) {
        (Some(lo), Some(hi)) => format!("(允许 {lo} 至 {hi}{unit})"),
        (Some(lo), None) => format!("(至少 {lo}{unit})"),
        (None, Some(hi)) => format!("(至多 {hi}{unit})"),
        (None, None) => String::new(),
    };
    format!("{} 测得 {}{unit}{allowed}", m.name, m.value)
}

/// A Tuya conformance check's name in 中文, by its id (`crate::ops::tuya::conform`).
fn conform_check_zh(id: &str) -> Option<&'static str> {
    Some(match id {
        "heartbeat" => "心跳(0x00)须在 3 秒内应答 00/01",
        "frame_version" => "MCU 帧版本须为 0x03",
        "product_info" => "产品信息(0x01)格式正确",
        "work_mode" => "工作模式(0x02)有应答",
        "wifi_state" => "Wi-Fi 状态(0x03)有确认",
        "status_all" => "状态查询(0x08)须上报每个数据点",
        "status_types" => "每个上报须符合其声明的类型与长度",
        "status_range" => "每个上报值须在数据点限值内",
        "status_burst" => "状态上报须在查询后 1 秒内全部到达",
        "status_unknown" => "不得上报设备配置中没有的数据点",
        "writable" => "每个可写数据点须被接受并重新上报(0x06)",
        "read_only_refused" => "只上报的数据点须拒绝写入(不上报)",
        "bad_checksum" => "校验和错误的帧须被丢弃",
        "unknown_command" => "未知命令(0x99)须被忽略",
        "ota" => "固件升级须被证实(0x0a/0x0b,之后 0x01 报出新版本)",
        "answer_time" => "每个应答须在 5 秒内",
        "frames_clean" => "MCU 帧不得有错误(校验和、长度、截断)",
        _ => return None,
    })
}

/// Provisioning's words in 中文 (`crate::ops::servo::provision`'s failures: no fresh servo,
/// several, no id left, a servo silent or garbled, values not read back, cancelled); others
/// as they came.
fn provision_zh(why: &str) -> String {
    let num = |s: &str| -> Option<String> {
        let n: String = s.chars().take_while(char::is_ascii_digit).collect();
        (!n.is_empty()).then_some(n)
    };
    if why == "cancelled by the operator" {
        return "操作员已停止".into();
    }
    if why == "no free id left in the plan's ids" {
        return "计划中的 ID 已全部分配".into();
    }
    if let Some(rest) = why.strip_prefix("no fresh servo (id ")
        && let Some(id) = num(rest)
    {
        return format!("没有新舵机(ID {id})在任何波特率下应答");
    }
    if let Some(rest) = why.strip_prefix("more than one servo answers at id ")
        && let Some(id) = num(rest)
    {
        return format!("ID {id} 上有多个舵机应答;总线上只留一个新舵机");
    }
    if why.starts_with("more than one servo: ") {
        return "有多个新舵机应答;总线上只留一个".into();
    }
    for (head, zh) in [
        ("servo ", "无应答"),
        ("garbled answer from servo ", "应答混乱"),
    ] {
        if let Some(rest) = why.strip_prefix(head)
            && let Some(id) = num(rest)
            && let Some(at) = rest.split(" at ").nth(1).and_then(num)
            && (zh == "应答混乱" || rest.contains("did not answer"))
        {
            return format!("舵机 {id} 在 {at} 波特下{zh}");
        }
    }
    if let Some(n) = num(why)
        && why.ends_with(" value(s) do not read back as written")
    {
        return format!("{n} 个值回读与写入不符");
    }
    why.to_string()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn provisioning_s_known_words_read_in_chinese() {
        let cases = [
            (
                "no fresh servo (id 0) answers at any baud rate",
                "没有新舵机(ID 0)在任何波特率下应答",
            ),
            (
                "servo 3 did not answer at 115200 baud (no answer to PING after 3 attempt(s))",
                "舵机 3 在 115200 波特下无应答",
            ),
            (
                "garbled answer from servo 1 at 1000000 baud (bad checksum)",
                "舵机 1 在 1000000 波特下应答混乱",
            ),
            (
                "2 value(s) do not read back as written",
                "2 个值回读与写入不符",
            ),
        ];
        for (en, zh) in cases {
            assert_eq!(provision_zh(en), zh, "{en}");
        }
    }
}
