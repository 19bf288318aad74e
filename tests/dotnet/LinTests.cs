// Checklist items 42-48: the LIN port (bit rates, monitors, the response table, sending), and
// a C# LIN master talking to a [[lin_node]] responder of canemud's configuration.
using System;
using System.Collections.Generic;
using Ixxat.Vci3.Bal;
using Ixxat.Vci3.Bal.Lin;
using NUnit.Framework;

namespace Canemu.Tests
{
  [TestFixture]
  public class LinTests
  {
    // alpha and beta each with a LIN controller (port 1) on lin0, and a responder "door" that
    // answers 30h with 01 02 03 (enhanced checksum).
    const string Lin =
        "[[bus]]\nname = \"can0\"\nkind = \"can\"\nbitrate = 500000\n\n" +
        "[[bus]]\nname = \"lin0\"\nkind = \"lin\"\nbitrate = 19200\n\n" +
        "[[device]]\nname = \"alpha\"\nmodel = \"ixxat-usb-to-can\"\ncontrollers = [\"can0\"]\nlin = [\"lin0\"]\n\n" +
        "[[device]]\nname = \"beta\"\nmodel = \"ixxat-usb-to-can\"\ncontrollers = [\"can0\"]\nlin = [\"lin0\"]\n\n" +
        "[[lin_node]]\nname = \"door\"\nbus = \"lin0\"\n\n" +
        "[[lin_node.response]]\nid = 0x30\ndata = [0x01, 0x02, 0x03]\n";
    // The same with a commander that asks for 10h (its own response 11 22) and 20h, each 10 ms
    // after the other (a header nobody answers takes the bus for 34 + 126 bits: 8.3 ms).
    const string WithCommander = Lin +
        "\n[[lin_node]]\nname = \"master\"\nbus = \"lin0\"\nschedule = \"s\"\n\n" +
        "[[lin_node.schedules]]\nname = \"s\"\nslots = [ { frame = 0x10, delay = \"10ms\" }, { frame = 0x20, delay = \"10ms\" } ]\n\n" +
        "[[lin_node.response]]\nid = 0x10\ndata = [0x11, 0x22]\n";

    // A LIN port opened as a program opens it: control unit, one monitor (active), the line
    // initialized in `mode` at 19200 bit/s (unless `init` is false) and started if asked.
    sealed class LinPort : IDisposable
    {
      public readonly IBalObject Bal;
      public readonly ILinControl Control;
      public readonly ILinMonitor Monitor;
      public readonly ILinMessageReader Reader;

      public LinPort(string device, LinOperatingModes mode, bool start = true, bool init = true)
      {
        Bal = T.Bal(device);
        Control = T.Open<ILinControl>(Bal, 1);
        Monitor = T.Open<ILinMonitor>(Bal, 1);
        Monitor.Initialize(64, false);
        Reader = Monitor.GetMessageReader();
        Monitor.Activate();
        if (init) Control.InitLine(new LinInitLine { OperatingMode = mode, Bitrate = LinBitrate.Lin19200Bit });
        if (start) Control.StartLine();
      }

      public List<LinMessage> Read(LinMessageType type = LinMessageType.Data)
      {
        var got = new List<LinMessage>();
        LinMessage m;
        while (Reader.ReadMessage(out m)) if (m.MessageType == type) got.Add(m);
        return got;
      }

      public void Dispose() { Reader.Dispose(); Monitor.Dispose(); Control.Dispose(); Bal.Dispose(); }
    }

    static LinMessage Frame(byte id, params byte[] data)
    {
      var m = new LinMessage { ProtId = id, MessageType = LinMessageType.Data, DataLength = (byte)data.Length, ExtendedCrc = true };
      for (int i = 0; i < data.Length; i++) m[i] = data[i];
      return m;
    }

    // The header alone (IdOnly) of `id`, for a response of `length` bytes that another node sends.
    static LinMessage Header(byte id, byte length)
    {
      var m = Frame(id);
      m.DataLength = length;
      m.IdOnly = true;
      return m;
    }

    static string Text(LinMessage m)
    {
      string s = m.ProtId.ToString("X2") + "#";
      for (int i = 0; i < m.DataLength; i++) s += m[i].ToString("X2");
      return s;
    }

    static List<string> Texts(List<LinMessage> got)
    {
      var l = new List<string>();
      foreach (var m in got) l.Add(Text(m));
      return l;
    }

    [Test]
    public void Item42_BitRatesFrom1000To20000OrAutoRate()
    {
      using (new Daemon(Lin))
      using (var bal = T.Bal("alpha"))
      using (var control = T.Open<ILinControl>(bal, 1))
      {
        Assert.AreEqual(1000, (int)LinBitrate.MinBitrate);
        Assert.AreEqual(20000, (int)LinBitrate.MaxBitrate);
        foreach (var bad in new[] { 999, 20001, 65535 })
        {
          var e = T.Throws(() => control.InitLine(new LinInitLine { OperatingMode = LinOperatingModes.Slave, Bitrate = (LinBitrate)bad }));
          Assert.AreEqual(0xE0010004u, e.ErrorCode);
          StringAssert.Contains("bit rate " + bad + " bit/s is not 1000..20000", e.Message);
        }
        foreach (var good in new[] { LinBitrate.MinBitrate, LinBitrate.Lin2400Bit, LinBitrate.Lin9600Bit, LinBitrate.Lin19200Bit, LinBitrate.MaxBitrate })
        {
          control.InitLine(new LinInitLine { OperatingMode = LinOperatingModes.Master, Bitrate = good });
          Assert.AreEqual(good, control.LineStatus.Bitrate);
          Assert.AreEqual(LinOperatingModes.Master, control.LineStatus.OperatingMode);
        }
        Assert.IsTrue(control.SupportsAutorate);
        control.InitLine(new LinInitLine { OperatingMode = LinOperatingModes.Slave, Bitrate = LinBitrate.AutoRate });
        var x = T.Throws(() => control.InitLine(new LinInitLine { OperatingMode = LinOperatingModes.Master, Bitrate = LinBitrate.AutoRate }));
        StringAssert.Contains("ILinControl.InitLine(Master, 0 bit/s)", x.Message);
      }
    }

    [Test]
    public void Item43_MonitorsReceiveWhileActiveAndOnlineEveryOneOfThem()
    {
      using (new Daemon(WithCommander))
      using (var alpha = new LinPort("alpha", LinOperatingModes.Slave, start: false))
      using (var idle = T.Open<ILinMonitor>(alpha.Bal, 1))
      {
        idle.Initialize(64, false);
        var idleReader = idle.GetMessageReader();
        T.Step(30);
        Assert.AreEqual(0, alpha.Read().Count, "the controller is not online");
        alpha.Control.StartLine();
        T.Step(30);
        LinMessage none;
        Assert.IsFalse(idleReader.ReadMessage(out none), "deactivated after open");
        var got = alpha.Read();
        Assert.Greater(got.Count, 0);
        Assert.AreEqual("10#1122", Text(got[0]));
        idle.Activate();
        T.Step(20);
        var a = Texts(alpha.Read());
        var b = new List<string>();
        LinMessage m;
        while (idleReader.ReadMessage(out m)) if (m.MessageType == LinMessageType.Data) b.Add(Text(m));
        Assert.Greater(a.Count, 0);
        CollectionAssert.AreEqual(a, b, "the distributor gives every monitor every frame");
      }
    }

    [Test]
    public void Item44_TheResponseTableAnswersIsUpdatedOnlineAndClearedByResetLine()
    {
      using (new Daemon(WithCommander))
      using (var alpha = new LinPort("alpha", LinOperatingModes.Slave, start: false))
      {
        var e = T.Throws(() => alpha.Control.WriteMessage(false, Frame(64, 1)));
        StringAssert.Contains("a response table entry must be LinMessageType.Data with an ID 0..63", e.Message);
        var sleep = Frame(0x20, 1);
        sleep.MessageType = LinMessageType.Sleep;
        T.Throws(() => alpha.Control.WriteMessage(false, sleep));
        alpha.Control.WriteMessage(false, Frame(0x20, 0xAA, 0xBB));
        alpha.Control.StartLine();
        T.Step(20);
        var got = alpha.Read();
        var twenty = got.FindAll(m => m.ProtId == 0x20);
        Assert.AreEqual(1, twenty.Count);
        Assert.AreEqual("20#AABB", Text(twenty[0]));
        Assert.IsTrue(twenty[0].SenderOfResponse, "alpha answered");
        Assert.IsFalse(got.Find(m => m.ProtId == 0x10).SenderOfResponse);
        alpha.Control.WriteMessage(false, Frame(0x20, 0xCC, 0xDD));  // online
        T.Step(20);
        Assert.AreEqual("20#CCDD", Text(alpha.Read().Find(m => m.ProtId == 0x20)));
        alpha.Control.StopLine();
        alpha.Control.StartLine();
        T.Step(20);
        Assert.AreEqual("20#CCDD", Text(alpha.Read().Find(m => m.ProtId == 0x20)), "StopLine keeps the table");
        alpha.Control.ResetLine();
        alpha.Control.InitLine(new LinInitLine { OperatingMode = LinOperatingModes.Slave, Bitrate = LinBitrate.Lin19200Bit });
        alpha.Control.StartLine();
        T.Step(20);
        got = alpha.Read();
        Assert.Greater(got.Count, 0);
        Assert.IsFalse(got.Exists(m => m.ProtId == 0x20), "ResetLine emptied the table: nobody answers 20h");
      }
    }

    [Test]
    public void Item45_TheControllerAnswersFromItsTableInMasterModeToo()
    {
      using (new Daemon(Lin))
      using (var alpha = new LinPort("alpha", LinOperatingModes.Master, start: false))
      using (var beta = new LinPort("beta", LinOperatingModes.Slave))
      {
        alpha.Control.WriteMessage(false, Frame(0x21, 0x05, 0x06));
        alpha.Control.StartLine();
        var header = Header(0x21, 2);
        alpha.Control.WriteMessage(true, header);
        T.Step(10);
        var own = alpha.Read();
        Assert.AreEqual(1, own.Count);
        Assert.AreEqual("21#0506", Text(own[0]));
        Assert.IsTrue(own[0].SenderOfResponse);
        CollectionAssert.AreEqual(new[] { "21#0506" }, Texts(beta.Read()));
      }
    }

    [Test]
    public void Item46_MasterSendsSleepWakeupAndHeaders()
    {
      using (new Daemon(Lin))
      using (var alpha = new LinPort("alpha", LinOperatingModes.Master))
      using (var beta = new LinPort("beta", LinOperatingModes.Slave))
      {
        alpha.Control.WriteMessage(true, new LinMessage { MessageType = LinMessageType.Sleep });
        T.Step(20);
        CollectionAssert.AreEqual(new[] { "3C#00FFFFFFFFFFFFFF" }, Texts(beta.Read()), "the go-to-sleep frame");
        alpha.Control.WriteMessage(true, new LinMessage { MessageType = LinMessageType.Wakeup });
        T.Step(20);
        Assert.AreEqual(1, beta.Read(LinMessageType.Wakeup).Count, "a wake-up pulse");
        var header = Header(0x30, 3);
        alpha.Control.WriteMessage(true, header);
        T.Step(20);
        var got = beta.Read();
        CollectionAssert.AreEqual(new[] { "30#010203" }, Texts(got), "the header alone; door answers");
        Assert.IsTrue(got[0].ExtendedCrc);
      }
    }

    [Test]
    public void Item47_ASlaveSendsOnlyWakeup()
    {
      using (new Daemon(Lin))
      using (var alpha = new LinPort("alpha", LinOperatingModes.Slave))
      using (var beta = new LinPort("beta", LinOperatingModes.Slave))
      {
        var e = T.Throws(() => alpha.Control.WriteMessage(true, Frame(0x10, 1)));
        Assert.AreEqual(0xE0010004u, e.ErrorCode);
        StringAssert.Contains("ILinControl.WriteMessage(True, Data id=0x10", e.Message);
        T.Throws(() => alpha.Control.WriteMessage(true, new LinMessage { MessageType = LinMessageType.Sleep }));
        alpha.Control.WriteMessage(true, new LinMessage { MessageType = LinMessageType.Wakeup });
        T.Step(20);
        Assert.AreEqual(1, beta.Read(LinMessageType.Wakeup).Count);
      }
    }

    [Test]
    public void Item48_WriteMessageNeverBlocksASecondSendWhileBusyIsRefused()
    {
      using (new Daemon(Lin))
      using (var alpha = new LinPort("alpha", LinOperatingModes.Master))
      {
        var header = Header(0x30, 3);
        alpha.Control.WriteMessage(true, header);
        var e = T.Throws(() => alpha.Control.WriteMessage(true, header));
        Assert.AreEqual(0xE0010013u, e.ErrorCode);
        StringAssert.Contains("the transmit buffer is busy with the previous message", e.Message);
        alpha.Control.WriteMessage(false, Frame(0x22, 9));  // the table is not the transmit buffer
        T.Step(20);
        alpha.Control.WriteMessage(true, header);
        T.Step(20);
        Assert.AreEqual(2, alpha.Read().Count);
      }
    }

    [Test]
    public void ACSharpMasterTalksToALinNodeResponder()
    {
      using (new Daemon(Lin))
      using (var alpha = new LinPort("alpha", LinOperatingModes.Master | LinOperatingModes.Errors))
      {
        ulong start = Emulator.Now;
        var header = Header(0x30, 3);
        for (int i = 0; i < 3; i++)
        {
          alpha.Control.WriteMessage(true, header);
          T.Step(10);
        }
        var got = alpha.Read();
        CollectionAssert.AreEqual(new[] { "30#010203", "30#010203", "30#010203" }, Texts(got));
        Assert.IsFalse(got[0].SenderOfResponse, "door answered, not alpha");
        // 34 header bits and 4 characters of 10 at 19200 bit/s: 3854 us after the request.
        Assert.AreEqual(start / 1000 + 3854, got[0].TimeStamp);
        Assert.AreEqual(10000u, got[1].TimeStamp - got[0].TimeStamp);
        // An identifier nobody answers: the master's own error message says so.
        var nobody = Header(0x31, 2);
        alpha.Control.WriteMessage(true, nobody);
        T.Step(20);
        var errors = alpha.Read(LinMessageType.Error);
        Assert.AreEqual(1, errors.Count);
        Assert.AreEqual((byte)LinMsgError.SlaveNoResponse, errors[0][0]);
      }
    }
  }
}
